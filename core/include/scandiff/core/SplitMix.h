// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! SplitMix64 (Steele, Lea and Flood 2014): a generator of eight bytes of
//! state, cheap to start anew for every item of a parallel loop (a triangle to
//! sample, a RANSAC hypothesis), so the draws of item i depend on the seed
//! and i only: the same results on any number of threads.

#include <cstdint>

namespace scandiff {

//! SplitMix64's output function: mixes the bits of a 64-bit value so that
//! neighbouring inputs give unrelated outputs.
inline std::uint64_t splitMix(std::uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

struct SplitMix64
{
    std::uint64_t state;
    //! Started from the mixed seed and the mixed item index (so seeds s and
    //! s + 1 are not one draw apart).
    SplitMix64(std::uint64_t seed, std::uint64_t item) : state(splitMix(splitMix(seed + 0x632be59bd9b4e019ULL) ^ splitMix(item))) {}
    std::uint64_t next() { return splitMix(state += 0x9e3779b97f4a7c15ULL); }
    //! Uniform in [0, 1).
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    //! Uniform in [0, n), n > 0 (Lemire's multiply-shift; the bias is below 2^-32 for n < 2^32).
    std::uint64_t below(std::uint64_t n) { return static_cast<std::uint64_t>((static_cast<unsigned __int128>(next()) * n) >> 64); }
};

} // namespace scandiff
