// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The few MPI calls scandiff-mpi makes, typed. MPI's C API is used as is
//! (Debian's OpenMPI); this header only spares the byte counting.

#include <mpi.h>

#include <cstdint>
#include <type_traits>
#include <vector>

namespace scandiff::mpi {

struct Communicator
{
    MPI_Comm comm = MPI_COMM_WORLD;
    int rank() const
    {
        int r = 0;
        MPI_Comm_rank(comm, &r);
        return r;
    }
    int size() const
    {
        int s = 1;
        MPI_Comm_size(comm, &s);
        return s;
    }
    void barrier() const { MPI_Barrier(comm); }
};

//! Every rank's vector, concatenated in rank order, on every rank.
template <class T>
std::vector<T> allGather(const Communicator& c, const std::vector<T>& mine)
{
    static_assert(std::is_trivially_copyable_v<T>, "sent as bytes");
    const int bytes = static_cast<int>(mine.size() * sizeof(T));
    std::vector<int> counts(static_cast<std::size_t>(c.size())), offsets(counts.size(), 0);
    MPI_Allgather(&bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, c.comm);
    for (std::size_t r = 1; r < counts.size(); ++r)
        offsets[r] = offsets[r - 1] + counts[r - 1];
    std::vector<T> all(static_cast<std::size_t>(offsets.back() + counts.back()) / sizeof(T));
    MPI_Allgatherv(mine.data(), bytes, MPI_BYTE, all.data(), counts.data(), offsets.data(), MPI_BYTE, c.comm);
    return all;
}

//! Every rank's vector, concatenated in rank order, on rank 0 (the others get an empty one).
template <class T>
std::vector<T> gatherToRoot(const Communicator& c, const std::vector<T>& mine)
{
    static_assert(std::is_trivially_copyable_v<T>, "sent as bytes");
    const int bytes = static_cast<int>(mine.size() * sizeof(T));
    const bool root = c.rank() == 0;
    std::vector<int> counts(root ? static_cast<std::size_t>(c.size()) : 1, 0), offsets(counts.size(), 0);
    MPI_Gather(&bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, c.comm);
    for (std::size_t r = 1; r < counts.size(); ++r)
        offsets[r] = offsets[r - 1] + counts[r - 1];
    std::vector<T> all(root ? static_cast<std::size_t>(offsets.back() + counts.back()) / sizeof(T) : 0);
    MPI_Gatherv(mine.data(), bytes, MPI_BYTE, all.data(), counts.data(), offsets.data(), MPI_BYTE, 0, c.comm);
    return all;
}

//! Collective. Sends rank r the counts[r] records of `send` that start at
//! record offsets[r] (a record: `recordElements` values of T), and fills
//! `received` with the records every rank sent this one, in rank order.
//! Counted in records, not bytes: an int then counts 2^31 records.
template <class T>
void exchangeRecords(const Communicator& c, const std::vector<T>& send, const std::vector<int>& counts,
                     const std::vector<int>& offsets, std::size_t recordElements, std::vector<T>& received)
{
    static_assert(std::is_trivially_copyable_v<T>, "sent as bytes");
    MPI_Datatype record;
    MPI_Type_contiguous(static_cast<int>(recordElements * sizeof(T)), MPI_BYTE, &record);
    MPI_Type_commit(&record);
    const auto ranks = static_cast<std::size_t>(c.size());
    std::vector<int> receiveCounts(ranks), receiveOffsets(ranks);
    MPI_Alltoall(counts.data(), 1, MPI_INT, receiveCounts.data(), 1, MPI_INT, c.comm);
    std::size_t total = 0;
    for (std::size_t r = 0; r < ranks; ++r) {
        receiveOffsets[r] = static_cast<int>(total);
        total += static_cast<std::size_t>(receiveCounts[r]);
    }
    received.resize(total * recordElements);
    MPI_Alltoallv(send.data(), counts.data(), offsets.data(), record, received.data(), receiveCounts.data(),
                  receiveOffsets.data(), record, c.comm);
    MPI_Type_free(&record);
}

inline std::uint64_t sumOverRanks(const Communicator& c, std::uint64_t mine)
{
    std::uint64_t total = 0;
    MPI_Allreduce(&mine, &total, 1, MPI_UINT64_T, MPI_SUM, c.comm);
    return total;
}

} // namespace scandiff::mpi
