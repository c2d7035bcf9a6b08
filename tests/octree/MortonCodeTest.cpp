// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/octree/MortonCode.h>

#include <gtest/gtest.h>

#include <random>

using namespace scandiff::octree;

namespace {

//! The code of the thesis's definition, built level by level: at each level one
//! triplet x y z saying on which side of the parent's mid-planes the cell lies.
MortonCode recursiveCode(std::uint32_t x, std::uint32_t y, std::uint32_t z, int levels)
{
    MortonCode code = 0;
    for (int level = levels - 1; level >= 0; --level) {
        code = (code << 3) | (((x >> level) & 1u) << 2) | (((y >> level) & 1u) << 1) | ((z >> level) & 1u);
    }
    return code;
}

} // namespace

TEST(MortonCode, MatchesRecursiveDescentAndDecodes)
{
    std::mt19937 rng(42);
    std::uniform_int_distribution<std::uint32_t> coordinate(0, kCellsPerAxisAtMaxLevel - 1);
    for (int i = 0; i < 10000; ++i) {
        const std::uint32_t x = coordinate(rng), y = coordinate(rng), z = coordinate(rng);
        const MortonCode code = encodeCell(x, y, z);
        EXPECT_EQ(code, recursiveCode(x, y, z, kMaxLevel));
        const CellCoordinates back = decodeCell(code);
        EXPECT_EQ(back.x, x);
        EXPECT_EQ(back.y, y);
        EXPECT_EQ(back.z, z);
    }
}

TEST(MortonCode, PrefixIsTheParentCell)
{
    const std::uint32_t x = 0x12345, y = 0x0abcd, z = 0x1f00f;
    const MortonCode full = encodeCell(x, y, z);
    for (int level = 1; level <= kMaxLevel; ++level) {
        const int drop = kMaxLevel - level;
        EXPECT_EQ(cellCodeAtLevel(full, level), encodeCell(x >> drop, y >> drop, z >> drop)) << "level " << level;
    }
}

TEST(MortonCode, ExtremesUseSixtyThreeBits)
{
    const std::uint32_t last = kCellsPerAxisAtMaxLevel - 1;
    EXPECT_EQ(encodeCell(last, last, last), (MortonCode(1) << 63) - 1);
    EXPECT_EQ(encodeCell(0, 0, 0), 0u);
}
