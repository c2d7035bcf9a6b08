// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/octree/Octree.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <stdexcept>

using namespace scandiff::octree;

namespace {

using Cloud = std::vector<Eigen::Vector3f>;

std::vector<Neighbour> bruteForceNearest(const Cloud& cloud, const Eigen::Vector3f& q, std::size_t k)
{
    std::vector<Neighbour> all;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        all.push_back({static_cast<std::uint32_t>(i), (cloud[i] - q).squaredNorm()});
    std::sort(all.begin(), all.end());
    all.resize(std::min(k, all.size()));
    return all;
}

std::vector<Neighbour> bruteForceRadius(const Cloud& cloud, const Eigen::Vector3f& q, float r)
{
    std::vector<Neighbour> all;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const float d2 = (cloud[i] - q).squaredNorm();
        if (d2 <= r * r)
            all.push_back({static_cast<std::uint32_t>(i), d2});
    }
    std::sort(all.begin(), all.end());
    return all;
}

Cloud randomCloud(std::size_t n, std::mt19937& rng)
{
    std::uniform_real_distribution<float> u(-5.0f, 5.0f);
    Cloud c(n);
    for (auto& p : c)
        p = {u(rng), u(rng), u(rng)};
    return c;
}

Cloud clusteredCloud(std::size_t n, std::mt19937& rng)
{
    std::normal_distribution<float> g(0.0f, 0.05f);
    std::uniform_real_distribution<float> u(-10.0f, 10.0f);
    Cloud centres(5);
    for (auto& c : centres)
        c = {u(rng), u(rng), u(rng)};
    Cloud c(n);
    for (std::size_t i = 0; i < n; ++i)
        c[i] = centres[i % centres.size()] + Eigen::Vector3f(g(rng), g(rng), g(rng));
    return c;
}

Cloud planarCloud(std::size_t n, std::mt19937& rng)
{
    std::uniform_real_distribution<float> u(0.0f, 3.0f);
    Cloud c(n);
    for (auto& p : c)
        p = {u(rng), u(rng), 1.5f};
    return c;
}

Cloud duplicateCloud(std::size_t n, std::mt19937& rng)
{
    Cloud base = randomCloud(n / 4, rng);
    Cloud c;
    for (int copy = 0; copy < 4; ++copy)
        c.insert(c.end(), base.begin(), base.end());
    return c;
}

void expectSame(const std::vector<Neighbour>& got, const std::vector<Neighbour>& expected, const std::string& where)
{
    ASSERT_EQ(got.size(), expected.size()) << where;
    for (std::size_t i = 0; i < got.size(); ++i) {
        EXPECT_EQ(got[i].index, expected[i].index) << where << " rank " << i;
        EXPECT_EQ(got[i].squaredDistance, expected[i].squaredDistance) << where << " rank " << i;
    }
}

struct Shape
{
    const char* name;
    Cloud (*make)(std::size_t, std::mt19937&);
};

const Shape kShapes[] = {{"random", randomCloud}, {"clustered", clusteredCloud}, {"planar", planarCloud}, {"duplicates", duplicateCloud}};

} // namespace

TEST(Octree, NearestEqualsBruteForceOnEveryShapeAndLevel)
{
    std::mt19937 rng(7);
    for (const Shape& shape : kShapes) {
        const Cloud cloud = shape.make(800, rng);
        const Octree tree(cloud.data(), cloud.size());
        const Cloud queries = randomCloud(40, rng);
        for (int level = 1; level <= kMaxLevel; level += (level < 10 ? 1 : 5)) {
            for (std::size_t k : {1u, 5u, 17u}) {
                std::vector<Neighbour> got;
                for (std::size_t qi = 0; qi < queries.size(); ++qi) {
                    // Queries both off the cloud and on its own points.
                    for (const Eigen::Vector3f& q : {queries[qi], cloud[qi * 7]}) {
                        tree.nearest(q, k, level, got);
                        expectSame(got, bruteForceNearest(cloud, q, k),
                                   std::string(shape.name) + " level " + std::to_string(level) + " k " + std::to_string(k));
                    }
                }
            }
        }
    }
}

TEST(Octree, RadiusEqualsBruteForceOnEveryShapeAndLevel)
{
    std::mt19937 rng(11);
    for (const Shape& shape : kShapes) {
        const Cloud cloud = shape.make(600, rng);
        const Octree tree(cloud.data(), cloud.size());
        const Cloud queries = randomCloud(30, rng);
        for (int level = 1; level <= 12; ++level) {
            for (float r : {0.05f, 0.7f, 3.0f}) {
                std::vector<Neighbour> got;
                for (const auto& q : queries) {
                    tree.withinRadius(q, r, level, got);
                    expectSame(got, bruteForceRadius(cloud, q, r), std::string(shape.name) + " level " + std::to_string(level));
                }
            }
        }
    }
}

TEST(Octree, SinglePointCloud)
{
    const Cloud cloud = {{1.0f, 2.0f, 3.0f}};
    const Octree tree(cloud.data(), cloud.size());
    std::vector<Neighbour> got;
    for (int level = 1; level <= kMaxLevel; ++level) {
        tree.nearest({10.0f, -4.0f, 0.0f}, 3, level, got);
        ASSERT_EQ(got.size(), 1u);
        EXPECT_EQ(got[0].index, 0u);
        EXPECT_FLOAT_EQ(got[0].squaredDistance, 81.0f + 36.0f + 9.0f);
    }
}

TEST(Octree, QueriesFarOutsideTheCubeAreExact)
{
    std::mt19937 rng(3);
    const Cloud cloud = randomCloud(300, rng);
    const Octree tree(cloud.data(), cloud.size());
    std::vector<Neighbour> got;
    for (const Eigen::Vector3f& q : {Eigen::Vector3f(100, 0, 0), Eigen::Vector3f(-50, 60, 7), Eigen::Vector3f(0, 0, -1e4f)}) {
        tree.nearest(q, 4, 8, got);
        expectSame(got, bruteForceNearest(cloud, q, 4), "far query");
    }
}

TEST(Octree, CellsAreContiguousAndStatisticsAgree)
{
    std::mt19937 rng(5);
    const Cloud cloud = clusteredCloud(2000, rng);
    const Octree tree(cloud.data(), cloud.size());
    const auto& codes = tree.sortedCodes();
    ASSERT_TRUE(std::is_sorted(codes.begin(), codes.end()));
    for (int level = 1; level <= kMaxLevel; ++level) {
        std::size_t cells = 0, largest = 0;
        std::size_t i = 0;
        while (i < codes.size()) {
            const MortonCode cell = cellCodeAtLevel(codes[i], level);
            const auto [first, last] = tree.cellRange(cell, level);
            EXPECT_EQ(first, i);
            std::size_t j = i;
            while (j < codes.size() && cellCodeAtLevel(codes[j], level) == cell)
                ++j;
            EXPECT_EQ(last, j);
            largest = std::max(largest, j - i);
            ++cells;
            i = j;
        }
        EXPECT_EQ(tree.levelStatistics(level).nonEmptyCells, cells) << "level " << level;
        EXPECT_EQ(tree.levelStatistics(level).maxPointsPerCell, largest) << "level " << level;
        EXPECT_DOUBLE_EQ(tree.levelStatistics(level).meanPointsPerCell, 2000.0 / static_cast<double>(cells));
    }
}

TEST(Octree, EveryPointLiesInItsCell)
{
    std::mt19937 rng(9);
    const Cloud cloud = randomCloud(500, rng);
    const Octree tree(cloud.data(), cloud.size());
    const int level = 6;
    const double l = tree.cellSize(level);
    for (std::size_t s = 0; s < tree.size(); ++s) {
        const CellCoordinates c = decodeCell(cellCodeAtLevel(tree.sortedCodes()[s], level));
        const Eigen::Vector3f& p = cloud[tree.sortedIndices()[s]];
        const std::uint32_t coords[3] = {c.x, c.y, c.z};
        for (int a = 0; a < 3; ++a) {
            EXPECT_GE(p[a], tree.box().min[a] + coords[a] * l - 1e-9);
            EXPECT_LE(p[a], tree.box().min[a] + (coords[a] + 1) * l + 1e-9);
        }
    }
}

TEST(Octree, SharedCubeGivesHomologousCodes)
{
    const Cloud a = {{0, 0, 0}, {1, 1, 1}};
    const Cloud b = {{0.001f, 0.001f, 0.001f}, {4, 4, 4}};
    const CubicBox both = CubicBox::enclosingBoth(CubicBox::enclosing(a.data(), a.size()), CubicBox::enclosing(b.data(), b.size()));
    const Octree ta(a.data(), a.size(), both), tb(b.data(), b.size(), both);
    // The two points near the origin share their cell down to a deep level.
    EXPECT_EQ(cellCodeAtLevel(ta.sortedCodes()[0], 10), cellCodeAtLevel(tb.sortedCodes()[0], 10));
}

TEST(Octree, RejectsEmptyNonFiniteAndOutsidePoints)
{
    const Cloud empty;
    EXPECT_THROW(Octree(empty.data(), 0), std::invalid_argument);
    const Cloud withNan = {{0, 0, 0}, {std::nanf(""), 1, 1}};
    try {
        Octree tree(withNan.data(), withNan.size());
        FAIL() << "NaN accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("point 1"), std::string::npos);
    }
    const Cloud withInf = {{0, 0, 0}, {INFINITY, 1, 1}};
    EXPECT_THROW(Octree(withInf.data(), withInf.size()), std::invalid_argument);
    const Cloud far = {{0, 0, 0}, {10, 10, 10}};
    CubicBox small;
    small.size = 1.0;
    EXPECT_THROW(Octree(far.data(), far.size(), small), std::invalid_argument);
}

TEST(Octree, LevelRuleOfIsprs2005)
{
    std::mt19937 rng(1);
    const Cloud cloud = randomCloud(4096, rng);
    const Octree tree(cloud.data(), cloud.size());
    const int level = tree.levelForMeanPopulation(10.0);
    EXPECT_LE(tree.levelStatistics(level).meanPointsPerCell, 10.0);
    EXPECT_GT(tree.levelStatistics(level - 1).meanPointsPerCell, 10.0);
}

TEST(Octree, LevelNearestATargetPopulation)
{
    std::mt19937 rng(2);
    const Cloud cloud = randomCloud(4096, rng);
    const Octree tree(cloud.data(), cloud.size());
    for (double target : {1.0, 8.0, 30.0, 500.0}) {
        const int level = tree.levelNearestMeanPopulation(target);
        const double gap = std::abs(std::log(tree.levelStatistics(level).meanPointsPerCell / target));
        for (int other = 1; other <= kMaxLevel; ++other)
            EXPECT_LE(gap, std::abs(std::log(tree.levelStatistics(other).meanPointsPerCell / target))) << target << " " << other;
    }
}

TEST(Octree, BatchNearestEqualsBruteForceAtEveryLevel)
{
    std::mt19937 rng(17);
    for (const Shape& shape : kShapes) {
        const Cloud cloud = shape.make(700, rng);
        const Octree tree(cloud.data(), cloud.size());
        Cloud queries = randomCloud(150, rng);
        queries.insert(queries.end(), cloud.begin(), cloud.begin() + 150); // on the cloud, and duplicates
        queries.push_back({1e3f, 0, 0});                                      // far outside the cube
        for (int level = 1; level <= kMaxLevel; ++level) {
            for (std::size_t k : {1u, 6u, 12u}) {
                std::vector<Neighbour> got;
                tree.nearestBatch(queries.data(), queries.size(), k, level, got);
                ASSERT_EQ(got.size(), queries.size() * k);
                for (std::size_t qi = 0; qi < queries.size(); ++qi) {
                    const auto expected = bruteForceNearest(cloud, queries[qi], k);
                    const std::vector<Neighbour> mine(got.begin() + static_cast<std::ptrdiff_t>(qi * k),
                                                      got.begin() + static_cast<std::ptrdiff_t>((qi + 1) * k));
                    expectSame(mine, expected, std::string(shape.name) + " level " + std::to_string(level) + " k " +
                                                   std::to_string(k) + " query " + std::to_string(qi));
                }
            }
        }
    }
}

TEST(Octree, BoundedBatchNearestEqualsBruteForceWithinTheDistance)
{
    // Only neighbours within the distance, the k nearest of them, the rest
    // missing: far queries and queries outside the cube included, at every level.
    std::mt19937 rng(23);
    for (const Shape& shape : kShapes) {
        const Cloud cloud = shape.make(700, rng);
        const Octree tree(cloud.data(), cloud.size());
        Cloud queries = randomCloud(120, rng);
        queries.insert(queries.end(), cloud.begin(), cloud.begin() + 60);
        queries.push_back({1e3f, 0, 0});
        queries.push_back({-30.0f, 0.5f, 0.5f});
        for (int level = 1; level <= kMaxLevel; ++level)
            for (std::size_t k : {1u, 6u})
                for (float distance : {0.0f, 0.3f, 1.0f, 3.0f, 20.0f}) {
                    std::vector<Neighbour> got;
                    tree.nearestBatch(queries.data(), queries.size(), k, level, got, nullptr, distance);
                    ASSERT_EQ(got.size(), queries.size() * k);
                    for (std::size_t qi = 0; qi < queries.size(); ++qi) {
                        std::vector<Neighbour> expected = bruteForceRadius(cloud, queries[qi], distance);
                        expected.resize(std::min(k, expected.size()));
                        std::vector<Neighbour> mine;
                        for (std::size_t r = 0; r < k; ++r)
                            if (got[qi * k + r].index != std::numeric_limits<std::uint32_t>::max())
                                mine.push_back(got[qi * k + r]);
                        expectSame(mine, expected, std::string(shape.name) + " level " + std::to_string(level) + " k " +
                                                       std::to_string(k) + " distance " + std::to_string(distance) + " query " +
                                                       std::to_string(qi));
                    }
                }
    }
    const Cloud one = {{0, 0, 0}};
    const Octree small(one.data(), one.size());
    std::vector<Neighbour> got;
    EXPECT_THROW(small.nearestBatch(one.data(), 1, 1, 3, got, nullptr, -1.0f), std::invalid_argument);
}

TEST(Octree, BatchPadsMissingNeighboursAndSkipsNaNQueries)
{
    const Cloud cloud = {{0, 0, 0}, {1, 0, 0}};
    const Octree tree(cloud.data(), cloud.size());
    const Cloud queries = {{0.2f, 0, 0}, {std::nanf(""), 0, 0}};
    std::vector<Neighbour> got;
    tree.nearestBatch(queries.data(), queries.size(), 3, 4, got);
    ASSERT_EQ(got.size(), 6u);
    EXPECT_EQ(got[0].index, 0u);
    EXPECT_EQ(got[1].index, 1u);
    EXPECT_EQ(got[2].index, std::numeric_limits<std::uint32_t>::max());
    EXPECT_TRUE(std::isinf(got[2].squaredDistance));
    for (int r = 3; r < 6; ++r)
        EXPECT_EQ(got[static_cast<std::size_t>(r)].index, std::numeric_limits<std::uint32_t>::max());
}

TEST(Octree, EqualCodesKeepTheirIndexOrder)
{
    std::mt19937 rng(2);
    const Cloud cloud = duplicateCloud(4000, rng);
    const Octree tree(cloud.data(), cloud.size());
    for (std::size_t i = 1; i < tree.size(); ++i) {
        if (tree.sortedCodes()[i] == tree.sortedCodes()[i - 1]) {
            EXPECT_LT(tree.sortedIndices()[i - 1], tree.sortedIndices()[i]);
        }
    }
    std::vector<std::uint32_t> all(tree.sortedIndices());
    std::sort(all.begin(), all.end());
    for (std::size_t i = 0; i < all.size(); ++i)
        ASSERT_EQ(all[i], i);
}

TEST(Octree, NeighbourCellsMatchDecodeAndEncode)
{
    std::mt19937 rng(23);
    const Cloud cloud = randomCloud(3000, rng);
    const Octree tree(cloud.data(), cloud.size());
    for (int level : {1, 3, 5}) {
        std::set<MortonCode> existing;
        tree.forEachCell(level, [&](MortonCode cell, std::size_t first, std::size_t last) {
            EXPECT_LT(first, last);
            existing.insert(cell);
        });
        EXPECT_EQ(existing.size(), tree.levelStatistics(level).nonEmptyCells);
        for (const MortonCode cell : existing) {
            const CellCoordinates c = decodeCell(cell);
            for (const auto connectivity : {Connectivity::Faces6, Connectivity::Edges18, Connectivity::Corners26}) {
                std::vector<MortonCode> expected;
                for (const MortonCode other : existing) {
                    const CellCoordinates o = decodeCell(other);
                    const long dx = std::labs(long(o.x) - long(c.x)), dy = std::labs(long(o.y) - long(c.y)),
                               dz = std::labs(long(o.z) - long(c.z));
                    if (std::max({dx, dy, dz}) != 1)
                        continue;
                    const long nonZero = (dx != 0) + (dy != 0) + (dz != 0);
                    if (nonZero <= static_cast<long>(connectivity == Connectivity::Faces6 ? 1 : connectivity == Connectivity::Edges18 ? 2 : 3))
                        expected.push_back(other);
                }
                EXPECT_EQ(tree.neighbourCells(cell, level, connectivity), expected) << "level " << level;
            }
        }
    }
}

TEST(Octree, BestLevelIsNearTheCheapestMeasuredLevel)
{
    // The thesis's setting (§4.5, Fig. 4.4) scaled down: two samplings of the
    // same surface, k = 1. "Cheapest" is measured with the work counters of the
    // batch query (a deterministic stand-in for time; wall times are in
    // docs/benchmarks.md).
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> u(0.0f, 10.0f);
    auto surface = [&](std::size_t count) {
        Cloud c(count);
        for (auto& p : c) {
            const float x = u(rng), y = u(rng);
            p = {x, y, std::sin(x) * std::cos(y)};
        }
        return c;
    };
    const Cloud reference = surface(60000), compared = surface(60000);
    const CubicBox cube = CubicBox::enclosingBoth(CubicBox::enclosing(reference.data(), reference.size()),
                                                  CubicBox::enclosing(compared.data(), compared.size()));
    const Octree referenceTree(reference.data(), reference.size(), cube);
    const Octree comparedTree(compared.data(), compared.size(), cube);
    const int chosen = referenceTree.bestLevelFor(comparedTree, 1);
    double cheapestCost = std::numeric_limits<double>::infinity();
    int cheapest = 0;
    std::vector<Neighbour> out;
    for (int level = 1; level <= 12; ++level) {
        QueryStatistics work;
        referenceTree.nearestBatch(compared.data(), compared.size(), 1, level, out, &work);
        const double cost = static_cast<double>(work.distances) + 20.0 * static_cast<double>(work.cellLookups) +
                            1000.0 * static_cast<double>(work.fullSearches);
        if (cost < cheapestCost) {
            cheapestCost = cost;
            cheapest = level;
        }
    }
    EXPECT_LE(std::abs(chosen - cheapest), 2) << "chosen " << chosen << ", cheapest " << cheapest;
}

TEST(Octree, BatchSettlesQueriesInCellsOnTheCubesLowFaces)
{
    // A flat cloud lies in the first layer of cells: their neighbourhoods start
    // at coordinate -1, which must be clipped, not wrapped around.
    std::mt19937 rng(41);
    const Cloud reference = planarCloud(20000, rng);
    Cloud queries = planarCloud(2000, rng);
    for (auto& q : queries)
        q = Eigen::Vector3f::Constant(0.1f) + q * 0.9f; // away from the x and y borders
    for (auto& q : queries)
        q.z() = 1.5f;
    const Octree tree(reference.data(), reference.size());
    std::vector<Neighbour> got;
    QueryStatistics work;
    tree.nearestBatch(queries.data(), queries.size(), 1, 6, got, &work);
    EXPECT_LT(work.fullSearches, queries.size() / 100);
    for (std::size_t i = 0; i < queries.size(); i += 50)
        EXPECT_EQ(got[i].squaredDistance, bruteForceNearest(reference, queries[i], 1)[0].squaredDistance);
}

TEST(Octree, ExtremeQueriesAndRadiiStayExact)
{
    std::mt19937 rng(43);
    const Cloud cloud = randomCloud(500, rng);
    const Octree tree(cloud.data(), cloud.size());
    std::vector<Neighbour> got;
    // A radius larger than everything returns every point.
    tree.withinRadius({0, 0, 0}, 1e20f, 1, got);
    EXPECT_EQ(got.size(), cloud.size());
    tree.withinRadius({0, 0, 0}, 1e20f, 21, got);
    EXPECT_EQ(got.size(), cloud.size());
    // A query absurdly far away still gets its exact nearest points.
    const Eigen::Vector3f far(3e12f, -2e12f, 1e12f);
    for (int level : {1, 10, 21}) {
        tree.nearest(far, 3, level, got);
        expectSame(got, bruteForceNearest(cloud, far, 3), "far query level " + std::to_string(level));
    }
    // A point just beyond a caller's cube is refused rather than mis-filed.
    CubicBox unit;
    unit.size = 1.0;
    const Cloud beyond = {{0.5f, 0.5f, 0.5f}, {1.0000004f, 0.5f, 0.5f}};
    EXPECT_THROW(Octree(beyond.data(), beyond.size(), unit), std::invalid_argument);
    const Cloud onFace = {{0.5f, 0.5f, 0.5f}, {1.0f, 0.5f, 0.5f}};
    const Octree faceTree(onFace.data(), onFace.size(), unit);
    faceTree.nearest({1.0f, 0.5f, 0.5f}, 1, 21, got);
    EXPECT_EQ(got[0].index, 1u);
}

TEST(Octree, BatchRadiusEqualsBruteForceForOwnAndOtherQueries)
{
    std::mt19937 rng(23);
    for (const Shape& shape : kShapes) {
        const Cloud cloud = shape.make(900, rng);
        const Octree tree(cloud.data(), cloud.size());
        Cloud others = randomCloud(60, rng);
        others.push_back({1e6f, 0.0f, 0.0f});                         // far outside the cube
        others.push_back({std::nanf(""), 0.0f, 0.0f});                // no neighbour
        others.push_back(cloud.front() + Eigen::Vector3f(0, 0, 40.0f)); // outside, but the sphere may reach in
        for (float r : {0.0f, 0.03f, 0.4f, 2.5f, 50.0f}) {
            for (const Cloud* queries : std::initializer_list<const Cloud*>{&cloud, &others}) {
                std::vector<std::vector<Neighbour>> got(queries->size());
                std::vector<int> visits(queries->size(), 0);
                tree.withinRadiusBatch(queries->data(), queries->size(), r,
                                       [&](std::uint32_t q, const Neighbour* list, std::size_t count) {
                                           got[q].assign(list, list + count);
                                           ++visits[q];
                                       });
                for (std::size_t q = 0; q < queries->size(); ++q) {
                    ASSERT_EQ(visits[q], 1) << shape.name << " query " << q;
                    std::sort(got[q].begin(), got[q].end());
                    const std::vector<Neighbour> expected =
                        (*queries)[q].allFinite() ? bruteForceRadius(cloud, (*queries)[q], r) : std::vector<Neighbour>{};
                    expectSame(got[q], expected, std::string(shape.name) + " radius " + std::to_string(r) + " query " + std::to_string(q));
                }
            }
        }
    }
    const Cloud cloud = randomCloud(10, rng);
    const Octree tree(cloud.data(), cloud.size());
    EXPECT_THROW(tree.withinRadiusBatch(cloud.data(), cloud.size(), -1.0f, [](std::uint32_t, const Neighbour*, std::size_t) {}),
                 std::invalid_argument);
}

//! The points of `cloud` inside the cylinder by its definition, with their
//! positions along the axis: (index, t) in index order.
std::vector<std::pair<std::uint32_t, double>> bruteForceCylinder(const Cloud& cloud, const Octree::CylinderQuery& q)
{
    std::vector<std::pair<std::uint32_t, double>> inside;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d v = cloud[i].cast<double>() - q.centre;
        const double t = v.dot(q.axis);
        if (std::abs(t) <= q.halfLength && v.squaredNorm() - t * t <= q.radius * q.radius)
            inside.emplace_back(static_cast<std::uint32_t>(i), t);
    }
    return inside;
}

TEST(Octree, CylinderBatchEqualsBruteForceWhateverTheCylinder)
{
    std::mt19937 rng(31);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> u(-6.0, 6.0);
    for (const Shape& shape : kShapes) {
        const Cloud cloud = shape.make(900, rng);
        const Octree tree(cloud.data(), cloud.size());
        std::vector<Octree::CylinderQuery> queries;
        // Short and long (a long thin oblique one is found by descent), on the
        // cloud's points and anywhere, along random directions and the axes.
        for (double radius : {0.0, 0.05, 0.4, 2.5})
            for (double halfLength : {0.0, 0.1, 1.0, 30.0})
                for (int k = 0; k < 6; ++k) {
                    Octree::CylinderQuery q;
                    q.centre = k % 2 ? cloud[static_cast<std::size_t>(k) * 97].cast<double>() : Eigen::Vector3d(u(rng), u(rng), u(rng));
                    q.axis = k < 2 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
                    q.radius = radius;
                    q.halfLength = halfLength;
                    queries.push_back(q);
                }
        // The planar cloud lies at z = 1.5: a cylinder ending exactly on it holds it (closed ends).
        Octree::CylinderQuery onEnd;
        onEnd.centre = {1.0, 1.0, 1.0};
        onEnd.radius = 1.0;
        onEnd.halfLength = 0.5;
        queries.push_back(onEnd);
        Octree::CylinderQuery far = onEnd;
        far.centre = {1e7, 0, 0};
        queries.push_back(far);
        const std::size_t usable = queries.size();
        Octree::CylinderQuery unusable = onEnd;
        unusable.centre.x() = std::nan("");
        queries.push_back(unusable);
        unusable = onEnd;
        unusable.axis.setZero();
        queries.push_back(unusable);
        unusable = onEnd;
        unusable.radius = -1;
        queries.push_back(unusable);

        std::vector<std::vector<std::pair<std::uint32_t, double>>> got(queries.size());
        std::vector<int> visits(queries.size(), 0);
        tree.withinCylinderBatch(queries.data(), queries.size(),
                                 [&](std::uint32_t q, const std::uint32_t* indices, const double* along, std::size_t count) {
                                     for (std::size_t i = 0; i < count; ++i)
                                         got[q].emplace_back(indices[i], along[i]);
                                     ++visits[q];
                                 });
        for (std::size_t q = 0; q < queries.size(); ++q) {
            ASSERT_EQ(visits[q], 1) << shape.name << " query " << q;
            std::sort(got[q].begin(), got[q].end());
            const auto expected = q < usable ? bruteForceCylinder(cloud, queries[q]) : std::vector<std::pair<std::uint32_t, double>>{};
            ASSERT_EQ(got[q], expected) << shape.name << " query " << q << " radius " << queries[q].radius << " half-length "
                                        << queries[q].halfLength;
        }
        if (std::string(shape.name) == "planar") {
            EXPECT_FALSE(got[usable - 2].empty()) << "the points on the cylinder's end";
        }
    }
}

TEST(Octree, BatchMomentsEqualTheBruteForceNeighbourhoods)
{
    std::mt19937 rng(29);
    for (const Shape& shape : kShapes) {
        const Cloud cloud = shape.make(700, rng);
        const Octree tree(cloud.data(), cloud.size());
        Cloud others = randomCloud(40, rng);
        others.push_back({1e6f, 0.0f, 0.0f});
        for (float r : {0.0f, 0.05f, 0.6f, 3.0f}) {
            for (const Cloud* queries : std::initializer_list<const Cloud*>{&cloud, &others}) {
                std::vector<NeighbourhoodMoments> got(queries->size());
                tree.radiusMomentsBatch(queries->data(), queries->size(), r,
                                        [&](std::uint32_t q, const NeighbourhoodMoments& m) { got[q] = m; });
                for (std::size_t q = 0; q < queries->size(); ++q) {
                    const std::vector<Neighbour> list = bruteForceRadius(cloud, (*queries)[q], r);
                    ASSERT_EQ(got[q].count, list.size()) << shape.name << " radius " << r << " query " << q;
                    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
                    double xx = 0, yz = 0;
                    for (const auto& n : list) {
                        const Eigen::Vector3d d = (cloud[n.index] - (*queries)[q]).cast<double>();
                        sum += d;
                        xx += d.x() * d.x();
                        yz += d.y() * d.z();
                    }
                    EXPECT_LT((got[q].sum - sum).norm(), 1e-9 * (1 + sum.norm())) << shape.name << " query " << q;
                    EXPECT_NEAR(got[q].products[0], xx, 1e-9 * (1 + xx)) << shape.name << " query " << q;
                    EXPECT_NEAR(got[q].products[4], yz, 1e-9 * (1 + std::abs(yz))) << shape.name << " query " << q;
                }
            }
        }
    }
}

TEST(Octree, BatchRadiusExactlyACellWide)
{
    // A grid on the cube's own cell boundaries, queried with radius = a cell:
    // every distance is a multiple of the spacing, many exactly the radius.
    Cloud grid;
    for (int i = 0; i <= 8; ++i)
        for (int j = 0; j <= 8; ++j)
            grid.push_back({0.125f * i, 0.125f * j, 0.0f});
    const Octree tree(grid.data(), grid.size(), CubicBox{Eigen::Vector3d::Zero(), 1.0});
    for (float r : {0.125f, 0.25f, 0.5f}) {
        std::vector<std::vector<Neighbour>> got(grid.size());
        tree.withinRadiusBatch(grid.data(), grid.size(), r, [&](std::uint32_t q, const Neighbour* list, std::size_t count) {
            got[q].assign(list, list + count);
        });
        for (std::size_t q = 0; q < grid.size(); ++q) {
            std::sort(got[q].begin(), got[q].end());
            expectSame(got[q], bruteForceRadius(grid, grid[q], r), "radius " + std::to_string(r));
        }
    }
}
