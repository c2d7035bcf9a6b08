// SPDX-License-Identifier: GPL-3.0-or-later
// What one symbol of LAZ's arithmetic decoder costs when it waits on the
// one before it (one stream) and when the processor can overlap several
// streams (1 to 8 decoded in turn, symbol by symbol). The figures "one
// stream" and "several streams" of docs/benchmarks.md (LAZ, ninth session)
// come from it: they bound what reordering the decoder's work can gain.
//
//   scandiff-laz-coder-streams [SYMBOLS=33] [RUNS=3]
//
// SYMBOLS is the alphabet (33: the integer coder's sizes, 256: its values);
// the symbols follow a geometric law (p = 1/4), about as skewed as the
// correction sizes of a scan.

#include "laz/ArithmeticCoder.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

namespace {

using namespace scandiff::io::detail::laz;

constexpr std::size_t kSymbolsPerStream = 2'000'000;
constexpr std::size_t kMaxStreams = 8;

//! Nanoseconds a symbol, decoding `Streams` streams in turn, a symbol of each.
template <std::size_t Streams>
double decodeInTurn(const std::vector<std::vector<unsigned char>>& streams, std::uint32_t symbols, std::uint64_t& checksum)
{
    std::vector<ArithmeticDecoder> decoders;
    std::vector<SymbolModel> models;
    for (std::size_t s = 0; s < Streams; ++s) {
        decoders.emplace_back(streams[s].data(), streams[s].data() + streams[s].size());
        models.emplace_back(symbols);
    }
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < kSymbolsPerStream; ++i)
        for (std::size_t s = 0; s < Streams; ++s)
            checksum += decoders[s].decodeSymbol(models[s]);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return seconds / double(kSymbolsPerStream * Streams) * 1e9;
}

} // namespace

int main(int argc, char** argv)
{
    const auto symbols = static_cast<std::uint32_t>(std::clamp(argc > 1 ? std::atoi(argv[1]) : 33, 2, 2048));
    const int runs = std::max(1, argc > 2 ? std::atoi(argv[2]) : 3);
    std::mt19937 random(1);
    std::geometric_distribution<std::uint32_t> law(0.25);
    std::vector<std::vector<unsigned char>> streams(kMaxStreams);
    for (std::vector<unsigned char>& stream : streams) {
        ArithmeticEncoder encoder;
        SymbolModel model(symbols);
        for (std::size_t i = 0; i < kSymbolsPerStream; ++i)
            encoder.encodeSymbol(model, std::min(law(random), symbols - 1));
        stream = encoder.done();
    }
    // The best of the runs for each count of streams.
    std::vector<double> best(6, 1e300);
    std::uint64_t checksum = 0;
    for (int r = 0; r < runs; ++r) {
        const double times[] = {decodeInTurn<1>(streams, symbols, checksum), decodeInTurn<2>(streams, symbols, checksum),
                                decodeInTurn<3>(streams, symbols, checksum), decodeInTurn<4>(streams, symbols, checksum),
                                decodeInTurn<6>(streams, symbols, checksum), decodeInTurn<8>(streams, symbols, checksum)};
        for (std::size_t i = 0; i < best.size(); ++i)
            best[i] = std::min(best[i], times[i]);
    }
    std::printf("%u symbols, ns a symbol (best of %d), streams decoded in turn:\n", symbols, runs);
    std::printf("  1: %.2f  2: %.2f  3: %.2f  4: %.2f  6: %.2f  8: %.2f   (checksum %llu)\n", best[0], best[1], best[2],
                best[3], best[4], best[5], static_cast<unsigned long long>(checksum));
    return 0;
}
