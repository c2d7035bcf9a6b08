// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Per-point results gathered through a file: every rank writes its values at
//! their points' input positions with MPI-IO (one collective write per field,
//! no rank ever holds all of them), then rank 0 reads them back in input order
//! while it writes the output.

#include "Mpi.h"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <vector>

namespace scandiff::mpi {

//! `planes[f][j]` goes to point indices[j] of plane f; a plane holds `total`
//! float32 values. Collective: every rank calls it with the same total and plane count.
void writeValuePlanes(const Communicator& c, const std::filesystem::path& file, std::uint64_t total,
                      const std::vector<std::uint64_t>& indices, const std::vector<std::vector<float>>& planes);

//! Rank 0's side: values [first, first + count) of plane f.
class ValuePlaneReader
{
public:
    ValuePlaneReader(const std::filesystem::path& file, std::uint64_t total);
    void read(std::size_t plane, std::uint64_t first, std::size_t count, float* out);

private:
    std::filesystem::path file_;
    std::ifstream in_;
    std::uint64_t total_;
};

} // namespace scandiff::mpi
