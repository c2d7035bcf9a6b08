// SPDX-License-Identifier: GPL-3.0-or-later
//! scandiff-octree-bench: the Morton-coded octree (octree/) against PCL's kd-tree
//! (KdTreeFLANN) and PCL's octree (OctreePointCloudSearch), on the same synthetic
//! scan-like data, the same queries and the same number of threads.
//! Results and the command that produced them: docs/benchmarks-octree.md.
//!
//! Data (deterministic, fixed seeds): a surface z = sin(x) cos(y) over a
//! 100 m x 100 m square, plus a vertical wall (the plane x = 50 m, 9 m high above
//! the terrain) holding 10 % of the points, with 3 mm Gaussian noise on every
//! coordinate. The "reference" and the "compared" clouds are two independent
//! samplings of that surface (seeds 1 and 2): the cloud/cloud setting of
//! thesis 000. Points are generated in random order, as a shuffled or merged
//! cloud would be; the query benchmarks also run with the queries sorted in
//! Morton order (the order a scan file often has: spatially coherent), because
//! a per-point search such as PCL's gets faster with coherent queries while
//! scandiff sorts its queries itself.
//!
//! Benchmarks
//!  - Build/*: time to build each index over N reference points (1 M and 10 M),
//!    and the index's own memory in bytes per point beyond the input points.
//!  - NN/*: exact 1-nearest neighbour of each of the 1 M compared points in the
//!    1 M reference, by scandiff's nearestBatch and by per-point PCL searches run
//!    with tbb::parallel_for. Every result is checked against PCL's kd-tree
//!    (outside the timed loops); a mismatch aborts the program.
//!  - LevelChoice: what the level heuristic costs (query octree + bestLevelFor).
//! Threads: TBB is capped at 2 (the benchmark machine has 2 cores); the
//! "threads:1" variants cap it at 1.

#include <scandiff/octree/Octree.h>

#include <benchmark/benchmark.h>

#include <pcl/common/common.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/octree/octree_search.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace {

using scandiff::octree::CubicBox;
using scandiff::octree::Neighbour;
using scandiff::octree::Octree;
using scandiff::octree::QueryStatistics;
using PclCloud = pcl::PointCloud<pcl::PointXYZ>;
using PclOctree = pcl::octree::OctreePointCloudSearch<pcl::PointXYZ>;

constexpr std::size_t kQueryPoints = 1'000'000;
constexpr int kThreads = 2;

// ---------------------------------------------------------------------------
// Data

//! N points of the synthetic surface (see the file comment), in random order.
std::vector<Eigen::Vector3f> makeSurface(std::size_t n, std::uint64_t seed)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> across(0.0f, 100.0f);
    std::uniform_real_distribution<float> up(0.0f, 9.0f);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::normal_distribution<float> noise(0.0f, 0.003f);
    std::vector<Eigen::Vector3f> points(n);
    for (auto& p : points) {
        if (unit(rng) < 0.1f) { // the wall, standing on the terrain
            const float y = across(rng);
            p = {50.0f, y, std::sin(50.0f) * std::cos(y) + up(rng)};
        } else {
            const float x = across(rng), y = across(rng);
            p = {x, y, std::sin(x) * std::cos(y)};
        }
        p += Eigen::Vector3f(noise(rng), noise(rng), noise(rng));
    }
    return points;
}

PclCloud::Ptr toPcl(const std::vector<Eigen::Vector3f>& points)
{
    PclCloud::Ptr cloud(new PclCloud);
    cloud->resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        (*cloud)[i].getVector3fMap() = points[i];
    return cloud;
}

//! Reference clouds by size, made on first use (10 M only when a 10 M benchmark runs).
struct ReferenceCloud
{
    std::vector<Eigen::Vector3f> points;
    PclCloud::Ptr pcl;
};
const ReferenceCloud& reference(std::size_t n)
{
    static std::map<std::size_t, std::unique_ptr<ReferenceCloud>> clouds;
    auto& slot = clouds[n];
    if (!slot) {
        slot = std::make_unique<ReferenceCloud>();
        slot->points = makeSurface(n, 1);
        slot->pcl = toPcl(slot->points);
    }
    return *slot;
}

//! The cloud/cloud query setting: 1 M compared points against the 1 M reference,
//! both octrees on one cube, the heuristic's level, and PCL kd-tree's answers
//! (the ground truth of every check).
struct QuerySetting
{
    const ReferenceCloud* ref = nullptr;
    CubicBox cube;
    std::unique_ptr<Octree> refTree;
    std::vector<Eigen::Vector3f> queries[2]; //!< [0] as generated (random order), [1] Morton order
    PclCloud::Ptr pclQueries[2];
    std::vector<std::uint32_t> toGenerated[2]; //!< query position -> index in the generated order
    int chosenLevel = 0;
    std::vector<float> truthDistance; //!< PCL kd-tree's squared distance, by generated index
    std::vector<int> truthIndex;
};

const QuerySetting& setting()
{
    static std::unique_ptr<QuerySetting> s;
    if (s)
        return *s;
    s = std::make_unique<QuerySetting>();
    s->ref = &reference(kQueryPoints);
    s->queries[0] = makeSurface(kQueryPoints, 2);
    s->cube = CubicBox::enclosingBoth(CubicBox::enclosing(s->ref->points.data(), s->ref->points.size()),
                                      CubicBox::enclosing(s->queries[0].data(), s->queries[0].size()));
    s->refTree = std::make_unique<Octree>(s->ref->points.data(), s->ref->points.size(), s->cube);
    const Octree queryTree(s->queries[0].data(), s->queries[0].size(), s->cube);
    s->chosenLevel = s->refTree->bestLevelFor(queryTree, 1);
    s->toGenerated[0].resize(kQueryPoints);
    for (std::uint32_t i = 0; i < kQueryPoints; ++i)
        s->toGenerated[0][i] = i;
    s->toGenerated[1] = queryTree.sortedIndices();
    s->queries[1].resize(kQueryPoints);
    for (std::size_t i = 0; i < kQueryPoints; ++i)
        s->queries[1][i] = s->queries[0][s->toGenerated[1][i]];
    for (int o = 0; o < 2; ++o)
        s->pclQueries[o] = toPcl(s->queries[o]);

    // Ground truth: PCL's kd-tree, exact (eps = 0, unlimited checks).
    pcl::KdTreeFLANN<pcl::PointXYZ> kdtree;
    kdtree.setInputCloud(s->ref->pcl);
    s->truthDistance.resize(kQueryPoints);
    s->truthIndex.resize(kQueryPoints);
    tbb::parallel_for(std::size_t(0), kQueryPoints, [&](std::size_t i) {
        pcl::Indices idx(1);
        std::vector<float> d2(1);
        kdtree.nearestKSearch((*s->pclQueries[0])[i], 1, idx, d2);
        s->truthIndex[i] = idx[0];
        s->truthDistance[i] = d2[0];
    });
    return *s;
}

//! Float squared distances summed in another order differ in the last bits:
//! Eigen's squaredNorm() (scandiff, PCL's octree) adds x² + (y² + z²), FLANN
//! (x² + y²) + z². Two results are "equal" within this relative tolerance (a
//! few float ulps), far below any real difference between two candidate points.
constexpr double kRoundingTolerance = 1e-6;

bool sameUpToRounding(double a, double b) { return std::abs(a - b) <= kRoundingTolerance * std::max(a, b); }

//! Aborts unless every query's squared distance equals PCL kd-tree's up to the
//! float summation order; the indices may differ only where both points are at
//! the same distance from the query (a tie, judged in double precision).
void verify(const char* what, const QuerySetting& s, int order, const std::vector<float>& distance,
            const std::vector<std::int64_t>& index)
{
    std::size_t bitwiseEqual = 0, rounding = 0, ties = 0;
    for (std::size_t i = 0; i < kQueryPoints; ++i) {
        const std::uint32_t g = s.toGenerated[order][i];
        if (index[i] < 0 || static_cast<std::size_t>(index[i]) >= s.ref->points.size() ||
            !sameUpToRounding(distance[i], s.truthDistance[g])) {
            std::fprintf(stderr,
                         "MISMATCH (%s): query %zu (generated index %u): squared distance %.9g (point %lld), "
                         "PCL kd-tree %.9g (point %d)\n",
                         what, i, g, static_cast<double>(distance[i]), static_cast<long long>(index[i]),
                         static_cast<double>(s.truthDistance[g]), s.truthIndex[g]);
            std::abort();
        }
        if (distance[i] == s.truthDistance[g])
            ++bitwiseEqual;
        else
            ++rounding;
        if (index[i] != s.truthIndex[g]) {
            const Eigen::Vector3d q = s.queries[order][i].cast<double>();
            const double mine = (s.ref->points[static_cast<std::size_t>(index[i])].cast<double>() - q).squaredNorm();
            const double theirs = (s.ref->points[static_cast<std::size_t>(s.truthIndex[g])].cast<double>() - q).squaredNorm();
            if (!sameUpToRounding(mine, theirs)) {
                std::fprintf(stderr, "MISMATCH (%s): query %zu: point %lld (%.12g) and PCL kd-tree's %d (%.12g) are no tie\n",
                             what, i, static_cast<long long>(index[i]), mine, s.truthIndex[g], theirs);
                std::abort();
            }
            ++ties;
        }
    }
    std::fprintf(stderr,
                 "verified %s: %zu queries agree with PCL kd-tree: %zu bitwise-equal distances, %zu equal up to "
                 "float rounding, %zu ties resolved to another point\n",
                 what, kQueryPoints, bitwiseEqual, rounding, ties);
}

// ---------------------------------------------------------------------------
// Memory

//! Bytes the allocator has handed out (all arenas, plus mmapped blocks), after
//! returning free pages: the index's heap is the difference around its build.
std::size_t heapBytes()
{
    malloc_trim(0);
    const struct mallinfo2 m = mallinfo2();
    return m.uordblks + m.hblkhd;
}

//! Resident set size, from /proc/self/statm.
std::size_t residentBytes()
{
    malloc_trim(0);
    std::ifstream statm("/proc/self/statm");
    std::size_t pages = 0, resident = 0;
    statm >> pages >> resident;
    return resident * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

//! Resets the process's peak resident size (VmHWM) to its current size (Linux >= 4.0).
void resetPeakResident()
{
    std::ofstream("/proc/self/clear_refs") << "5";
}

//! Peak resident size since the last reset, from /proc/self/status.
std::size_t peakResidentBytes()
{
    std::ifstream status("/proc/self/status");
    std::string key;
    std::size_t kb = 0;
    while (status >> key)
        if (key == "VmHWM:") {
            status >> kb;
            break;
        }
    return kb * 1024;
}

//! Memory around one build: call before() with the timing paused, build, then after().
struct MemoryProbe
{
    std::size_t heap = 0, rss = 0;
    void before()
    {
        heap = heapBytes();
        rss = residentBytes();
        resetPeakResident();
    }
    //! heap_B/pt: allocator bytes the index keeps (mallinfo2 delta); rss_B/pt: the
    //! same seen as resident pages; peak_B/pt: the build's transient peak above the start.
    void after(benchmark::State& state, std::size_t n)
    {
        const double peak = static_cast<double>(peakResidentBytes()) - static_cast<double>(rss);
        const double points = static_cast<double>(n);
        state.counters["heap_B/pt"] = (static_cast<double>(heapBytes()) - static_cast<double>(heap)) / points;
        state.counters["rss_B/pt"] = (static_cast<double>(residentBytes()) - static_cast<double>(rss)) / points;
        state.counters["peak_B/pt"] = peak / points;
    }
};

// ---------------------------------------------------------------------------
// Build time and memory. Each iteration builds the index from the input points
// (bounding box included: scandiff computes its cube, PCL its own box); the
// destruction of the previous index is outside the timing.

void Build_Scandiff(benchmark::State& state)
{
    const auto n = static_cast<std::size_t>(state.range(0));
    // PCL's builds are single-threaded; the octree's uses TBB (argument 2: threads).
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(1)));
    const ReferenceCloud& ref = reference(n);
    std::unique_ptr<Octree> tree;
    MemoryProbe memory;
    for (auto _ : state) {
        state.PauseTiming();
        tree.reset();
        memory.before();
        state.ResumeTiming();
        tree = std::make_unique<Octree>(ref.points.data(), n, std::nullopt);
        state.PauseTiming();
        memory.after(state, n);
        state.ResumeTiming();
    }
    // The octree's own arrays, exactly: a 64-bit code and a 32-bit index per point.
    state.counters["index_B/pt"] =
        static_cast<double>(tree->sortedCodes().capacity() * sizeof(scandiff::octree::MortonCode) +
                            tree->sortedIndices().capacity() * sizeof(std::uint32_t)) /
        static_cast<double>(n);
}

void Build_PclKdTree(benchmark::State& state)
{
    const auto n = static_cast<std::size_t>(state.range(0));
    const ReferenceCloud& ref = reference(n);
    std::unique_ptr<pcl::KdTreeFLANN<pcl::PointXYZ>> tree;
    MemoryProbe memory;
    for (auto _ : state) {
        state.PauseTiming();
        tree.reset();
        memory.before();
        state.ResumeTiming();
        // Copies the points into FLANN's array, then builds a single kd-tree (15 points per leaf).
        tree = std::make_unique<pcl::KdTreeFLANN<pcl::PointXYZ>>();
        tree->setInputCloud(ref.pcl);
        state.PauseTiming();
        memory.after(state, n);
        state.ResumeTiming();
    }
}

//! PCL's octree leaf size: a voxel of side r on a surface of S m² sampled by N
//! points holds about N r² / S points; we aim at 4 (S ≈ 12,000 m², the terrain
//! with its slopes plus the wall): r = sqrt(4 S / N), 0.22 m for 1 M points and
//! 0.069 m for 10 M. Benchmarks may override it (argument 1, in mm).
double pclOctreeResolution(std::size_t n) { return std::sqrt(4.0 * 12000.0 / static_cast<double>(n)); }

std::unique_ptr<PclOctree> buildPclOctree(const PclCloud::Ptr& cloud, double resolution)
{
    auto tree = std::make_unique<PclOctree>(resolution);
    tree->setInputCloud(cloud);
    tree->addPointsFromInputCloud();
    return tree;
}

void Build_PclOctree(benchmark::State& state)
{
    const auto n = static_cast<std::size_t>(state.range(0));
    const ReferenceCloud& ref = reference(n);
    const double resolution = pclOctreeResolution(n);
    std::unique_ptr<PclOctree> tree;
    MemoryProbe memory;
    for (auto _ : state) {
        state.PauseTiming();
        tree.reset();
        memory.before();
        state.ResumeTiming();
        tree = buildPclOctree(ref.pcl, resolution);
        state.PauseTiming();
        memory.after(state, n);
        state.ResumeTiming();
    }
    state.counters["resolution_m"] = resolution;
    state.counters["pts/leaf"] = static_cast<double>(n) / static_cast<double>(tree->getLeafCount());
    state.counters["depth"] = static_cast<double>(tree->getTreeDepth());
}

// ---------------------------------------------------------------------------
// 1-NN of the 1 M compared points in the 1 M reference.

//! scandiff nearestBatch(k = 1). Arguments: level offset from the heuristic's
//! choice (the sweep shows whether the choice is the fastest level), query order
//! (0 generated, 1 Morton), threads. The timing includes everything nearestBatch
//! does: sorting the queries by cell, gathering each cell's neighbourhood, the
//! full searches of the queries it does not settle.
void NN_Scandiff(benchmark::State& state)
{
    const QuerySetting& s = setting();
    const int level = s.chosenLevel + static_cast<int>(state.range(0));
    const int order = static_cast<int>(state.range(1));
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(2)));
    std::vector<Neighbour> out;
    QueryStatistics stats;
    for (auto _ : state) {
        s.refTree->nearestBatch(s.queries[order].data(), kQueryPoints, 1, level, out, &stats);
        benchmark::DoNotOptimize(out.data());
    }
    std::vector<float> distance(kQueryPoints);
    std::vector<std::int64_t> index(kQueryPoints);
    for (std::size_t i = 0; i < kQueryPoints; ++i) {
        distance[i] = out[i].squaredDistance;
        index[i] = out[i].index;
    }
    verify(("scandiff level " + std::to_string(level)).c_str(), s, order, distance, index);
    state.counters["level"] = level;
    state.counters["chosen"] = level == s.chosenLevel;
    state.counters["cell_m"] = s.refTree->cellSize(level);
    state.counters["ref_pts/cell"] = s.refTree->levelStatistics(level).meanPointsPerCell;
    state.counters["dist/query"] = static_cast<double>(stats.distances) / kQueryPoints;
    state.counters["full_search_%"] = 100.0 * static_cast<double>(stats.fullSearches) / kQueryPoints;
}

//! Per-point PCL searches of k neighbours over the queries with
//! tbb::parallel_for (one shared index, per-thread result vectors), results
//! stored like nearestBatch's: query i's j-th neighbour at i * k + j.
template <typename Search>
void pclBatch(const PclCloud& queries, std::size_t k, std::vector<float>& distance, std::vector<std::int64_t>& index,
              Search&& search)
{
    struct Scratch
    {
        pcl::Indices idx;
        std::vector<float> d2;
    };
    distance.resize(queries.size() * k);
    index.resize(queries.size() * k);
    tbb::enumerable_thread_specific<Scratch> scratch;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, queries.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        Scratch& t = scratch.local();
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            search(queries[i], static_cast<int>(k), t.idx, t.d2);
            for (std::size_t j = 0; j < k; ++j) {
                index[i * k + j] = t.idx[j];
                distance[i * k + j] = t.d2[j];
            }
        }
    });
}

//! PCL KdTreeFLANN::nearestKSearch(point, 1) per query. Arguments: query order, threads.
//! FLANN's single kd-tree search is const and keeps its state on the stack, so
//! one index is shared by the threads (as PCL's own *OMP estimators do).
void NN_PclKdTree(benchmark::State& state)
{
    const QuerySetting& s = setting();
    const int order = static_cast<int>(state.range(0));
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(1)));
    pcl::KdTreeFLANN<pcl::PointXYZ> kdtree;
    kdtree.setInputCloud(s.ref->pcl);
    std::vector<float> distance(kQueryPoints);
    std::vector<std::int64_t> index(kQueryPoints);
    for (auto _ : state) {
        pclBatch(*s.pclQueries[order], 1, distance, index, [&](const pcl::PointXYZ& q, int k, pcl::Indices& idx, std::vector<float>& d2) {
            kdtree.nearestKSearch(q, k, idx, d2);
        });
        benchmark::DoNotOptimize(distance.data());
    }
    verify("PCL kd-tree", s, order, distance, index);
}

//! PCL OctreePointCloudSearch::nearestKSearch(point, 1) per query. Arguments:
//! query order, threads, leaf resolution in mm (0: pclOctreeResolution). The
//! method is not const in PCL 1.13, but it only reads the tree (its search state
//! is local to the call; pcl::search::Octree calls it from const methods that
//! PCL's OMP estimators share between threads), so concurrent reads are safe.
void NN_PclOctree(benchmark::State& state)
{
    const QuerySetting& s = setting();
    const int order = static_cast<int>(state.range(0));
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(1)));
    const double resolution = state.range(2) > 0 ? static_cast<double>(state.range(2)) / 1000.0 : pclOctreeResolution(kQueryPoints);
    const auto tree = buildPclOctree(s.ref->pcl, resolution);
    std::vector<float> distance(kQueryPoints);
    std::vector<std::int64_t> index(kQueryPoints);
    for (auto _ : state) {
        pclBatch(*s.pclQueries[order], 1, distance, index, [&](const pcl::PointXYZ& q, int k, pcl::Indices& idx, std::vector<float>& d2) {
            tree->nearestKSearch(q, k, idx, d2);
        });
        benchmark::DoNotOptimize(distance.data());
    }
    verify("PCL octree", s, order, distance, index);
    state.counters["resolution_m"] = resolution;
    state.counters["pts/leaf"] = static_cast<double>(kQueryPoints) / static_cast<double>(tree->getLeafCount());
}

// ---------------------------------------------------------------------------
// k nearest neighbours (k = 12, the local models' default) of the 1 M compared
// points, queries in Morton order (as cloudToCloud submits them).

constexpr std::size_t kNeighbours = 12;

//! scandiff nearestBatch(k = 12). Arguments: level offset from the level
//! cloudToCloud uses for k neighbours (cells of about 3 k points), threads.
//! The k distances of every query are checked against PCL's kd-tree.
void KNN_Scandiff(benchmark::State& state)
{
    const QuerySetting& s = setting();
    const int level = s.refTree->levelNearestMeanPopulation(3.0 * kNeighbours) + static_cast<int>(state.range(0));
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(1)));
    std::vector<Neighbour> out;
    QueryStatistics stats;
    for (auto _ : state) {
        s.refTree->nearestBatch(s.queries[1].data(), kQueryPoints, kNeighbours, level, out, &stats);
        benchmark::DoNotOptimize(out.data());
    }
    // Check against PCL (outside the timing).
    pcl::KdTreeFLANN<pcl::PointXYZ> kdtree;
    kdtree.setInputCloud(s.ref->pcl);
    std::vector<float> distance;
    std::vector<std::int64_t> index;
    pclBatch(*s.pclQueries[1], kNeighbours, distance, index, [&](const pcl::PointXYZ& q, int k, pcl::Indices& idx, std::vector<float>& d2) {
        kdtree.nearestKSearch(q, k, idx, d2);
    });
    for (std::size_t i = 0; i < out.size(); ++i)
        if (!sameUpToRounding(out[i].squaredDistance, distance[i])) {
            std::fprintf(stderr, "MISMATCH: scandiff's k-NN squared distance %zu is %.9g, PCL kd-tree's %.9g\n", i,
                         static_cast<double>(out[i].squaredDistance), static_cast<double>(distance[i]));
            std::abort();
        }
    state.counters["level"] = level;
    state.counters["ref_pts/cell"] = s.refTree->levelStatistics(level).meanPointsPerCell;
    state.counters["dist/query"] = static_cast<double>(stats.distances) / kQueryPoints;
    state.counters["full_search_%"] = 100.0 * static_cast<double>(stats.fullSearches) / kQueryPoints;
}

//! PCL KdTreeFLANN::nearestKSearch(point, 12) per query, Morton-ordered queries. Argument: threads.
void KNN_PclKdTree(benchmark::State& state)
{
    const QuerySetting& s = setting();
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(0)));
    pcl::KdTreeFLANN<pcl::PointXYZ> kdtree;
    kdtree.setInputCloud(s.ref->pcl);
    std::vector<float> distance;
    std::vector<std::int64_t> index;
    for (auto _ : state) {
        pclBatch(*s.pclQueries[1], kNeighbours, distance, index, [&](const pcl::PointXYZ& q, int k, pcl::Indices& idx, std::vector<float>& d2) {
            kdtree.nearestKSearch(q, k, idx, d2);
        });
        benchmark::DoNotOptimize(distance.data());
    }
}

//! What choosing the level costs in the cloud/cloud setting: the query octree
//! (on the common cube) and bestLevelFor. Not part of the NN timings above.
void LevelChoice(benchmark::State& state)
{
    const QuerySetting& s = setting();
    int level = 0;
    for (auto _ : state) {
        const Octree queryTree(s.queries[0].data(), kQueryPoints, s.cube);
        level = s.refTree->bestLevelFor(queryTree, 1);
        benchmark::DoNotOptimize(level);
    }
    state.counters["level"] = level;
}

} // namespace

BENCHMARK(Build_Scandiff)
    ->ArgNames({"points", "threads"})
    ->Args({1'000'000, kThreads})->Args({10'000'000, kThreads})->Args({1'000'000, 1})->Args({10'000'000, 1})
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(Build_PclKdTree)->ArgName("points")->Arg(1'000'000)->Arg(10'000'000)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(Build_PclOctree)->ArgName("points")->Arg(1'000'000)->Arg(10'000'000)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// Level sweep (generated order, 2 threads), then the chosen level with Morton-ordered queries and on 1 thread.
BENCHMARK(NN_Scandiff)
    ->ArgNames({"level_offset", "order", "threads"})
    ->Args({-3, 0, kThreads})->Args({-2, 0, kThreads})->Args({-1, 0, kThreads})->Args({0, 0, kThreads})
    ->Args({1, 0, kThreads})->Args({2, 0, kThreads})->Args({3, 0, kThreads})
    ->Args({0, 1, kThreads})->Args({0, 0, 1})
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);
BENCHMARK(NN_PclKdTree)
    ->ArgNames({"order", "threads"})
    ->Args({0, kThreads})->Args({1, kThreads})->Args({0, 1})->Args({1, 1})
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);
BENCHMARK(NN_PclOctree)
    ->ArgNames({"order", "threads", "resolution_mm"})
    ->Args({0, kThreads, 0})->Args({1, kThreads, 0})->Args({0, 1, 0})
    // PCL's octree at half and twice the default leaf size (0.22 m for 1 M points), to show it at its best.
    ->Args({1, kThreads, 110})->Args({1, kThreads, 440})
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(KNN_Scandiff)
    ->ArgNames({"level_offset", "threads"})
    ->Args({-1, kThreads})->Args({0, kThreads})->Args({1, kThreads})
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);
BENCHMARK(KNN_PclKdTree)->ArgName("threads")->Arg(kThreads)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(LevelChoice)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

int main(int argc, char** argv)
{
    // Both cores, whatever the machine: the comparison is at equal thread counts.
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, kThreads);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return 1;
    benchmark::AddCustomContext("data", "z = sin(x)cos(y) on 100 m x 100 m + wall x = 50 m (10 %), 3 mm noise; seeds 1 (reference), 2 (compared)");
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
