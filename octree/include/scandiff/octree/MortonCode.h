// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Morton (Z-order) codes of thesis 000, §4.3: per level one triplet of bits,
//! level 1 in the most significant bits. We order each triplet x y z, x highest
//! (Tab. 4.1 of the thesis; the order only has to be consistent).
//! 21 levels x 3 bits = 63 bits of a 64-bit code.

#include <cstdint>

namespace scandiff::octree {

using MortonCode = std::uint64_t;

constexpr int kMaxLevel = 21;
constexpr std::uint32_t kCellsPerAxisAtMaxLevel = 1u << kMaxLevel;

//! Spreads the low 21 bits of v so that bit i lands on bit 3i.
constexpr std::uint64_t spreadBits3(std::uint64_t v)
{
    v &= 0x1fffff;
    v = (v | (v << 32)) & 0x1f00000000ffffULL;
    v = (v | (v << 16)) & 0x1f0000ff0000ffULL;
    v = (v | (v << 8)) & 0x100f00f00f00f00fULL;
    v = (v | (v << 4)) & 0x10c30c30c30c30c3ULL;
    v = (v | (v << 2)) & 0x1249249249249249ULL;
    return v;
}

//! Inverse of spreadBits3: gathers bits 0, 3, 6, ... into the low 21 bits.
constexpr std::uint32_t compactBits3(std::uint64_t v)
{
    v &= 0x1249249249249249ULL;
    v = (v ^ (v >> 2)) & 0x10c30c30c30c30c3ULL;
    v = (v ^ (v >> 4)) & 0x100f00f00f00f00fULL;
    v = (v ^ (v >> 8)) & 0x1f0000ff0000ffULL;
    v = (v ^ (v >> 16)) & 0x1f00000000ffffULL;
    v = (v ^ (v >> 32)) & 0x1fffff;
    return static_cast<std::uint32_t>(v);
}

//! Code of the cell with integer coordinates (x, y, z) at a level: 3*level bits.
constexpr MortonCode encodeCell(std::uint32_t x, std::uint32_t y, std::uint32_t z)
{
    return (spreadBits3(x) << 2) | (spreadBits3(y) << 1) | spreadBits3(z);
}

struct CellCoordinates
{
    std::uint32_t x = 0, y = 0, z = 0;
};

constexpr CellCoordinates decodeCell(MortonCode code)
{
    return {compactBits3(code >> 2), compactBits3(code >> 1), compactBits3(code)};
}

//! The prefix of a full-depth code that names its cell at `level`.
constexpr MortonCode cellCodeAtLevel(MortonCode fullCode, int level)
{
    return fullCode >> (3 * (kMaxLevel - level));
}

} // namespace scandiff::octree
