// SPDX-License-Identifier: GPL-3.0-or-later
// Records-only LAZ decoding: what the reader's decompression costs without
// building a cloud, on a chosen number of threads, the best of a few runs.
// The numbers "records only, one core" in docs/benchmarks.md and docs/laz.md
// come from it; run under `valgrind --tool=callgrind` it counts the
// instructions a point takes.
//
//   scandiff-laz-decode FILE.laz [THREADS=1] [RUNS=3]

#include "las/LasLayout.h"
#include "laz/LazDecoder.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace {

template <class T>
T at(const std::string& bytes, std::size_t offset)
{
    if (offset + sizeof(T) > bytes.size())
        throw std::runtime_error("the file is too short for its header");
    T value;
    std::memcpy(&value, bytes.data() + offset, sizeof value);
    return value;
}

} // namespace

int main(int argc, char** argv)
{
    using namespace scandiff::io::detail;
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s FILE.laz [THREADS=1] [RUNS=3]\n", argv[0]);
        return 2;
    }
    try {
        std::ifstream in(argv[1], std::ios::binary);
        std::stringstream content;
        content << in.rdbuf();
        const std::string bytes = content.str();
        const int threads = argc > 2 ? std::max(1, std::atoi(argv[2])) : 1;
        const int runs = argc > 3 ? std::max(1, std::atoi(argv[3])) : 3;
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));

        // The LAS header's fields this needs (the reader's parser is private
        // to LasFormat.cpp); a VLR header holds its record id at byte 18 and
        // its payload length at byte 20.
        using namespace las;
        std::size_t vlr = at<std::uint16_t>(bytes, hdr::headerSize), payload = 0, payloadLength = 0;
        for (std::uint32_t v = 0; v < at<std::uint32_t>(bytes, hdr::vlrCount); ++v) {
            if (at<std::uint16_t>(bytes, vlr + 18) == kLaszipRecordId) {
                payload = vlr + kVlrHeaderSize;
                payloadLength = at<std::uint16_t>(bytes, vlr + 20);
                break;
            }
            vlr += kVlrHeaderSize + at<std::uint16_t>(bytes, vlr + 20);
        }
        if (payload == 0)
            throw std::runtime_error("no LASzip record: not a LAZ file");
        const std::size_t recordLength = at<std::uint16_t>(bytes, hdr::recordLength);
        const std::uint64_t count = at<std::uint8_t>(bytes, hdr::versionMinor) >= 4 ? at<std::uint64_t>(bytes, hdr::pointCount)
                                                                                     : at<std::uint32_t>(bytes, hdr::legacyPointCount);
        const LazLayout layout = parseLazLayout(argv[1], bytes.data() + payload, payloadLength, recordLength);
        const auto chunks = readLazChunks(argv[1], bytes.data(), bytes.size(), at<std::uint32_t>(bytes, hdr::offsetToPoints), layout,
                                          recordLength, count);

        double best = 1e300;
        std::uint64_t checksum = 0; // one byte of every 997th record, so that nothing is optimised away
        for (int r = 0; r < runs; ++r) {
            const auto start = std::chrono::steady_clock::now();
            decompressLazRecords(
                argv[1], bytes.data(), bytes.size(), chunks, layout, recordLength, 0, count,
                [&](std::uint64_t, const char* records, std::size_t n) {
                    for (std::size_t i = 0; i < n; i += 997)
                        checksum += static_cast<unsigned char>(records[i * recordLength]);
                },
                [](std::size_t) {});
            best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        }
        std::printf("%s: %llu points, %d thread(s), best of %d: %.3f s, %.2f M points/s (checksum %llu)\n", argv[1],
                    static_cast<unsigned long long>(count), threads, runs, best, static_cast<double>(count) / best / 1e6,
                    static_cast<unsigned long long>(checksum));
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s: %s\n", argv[1], e.what());
        return 1;
    }
}
