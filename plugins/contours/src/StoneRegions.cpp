// SPDX-License-Identifier: GPL-3.0-or-later
#include "StoneRegions.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>
#include <utility>

namespace scandiff::plugins {

namespace {

// A square grid's twelve nearest neighbours reach two steps along its axes:
// enough to see a joint line on both sides of a one-point gap in it.
constexpr std::size_t kNeighbours = 12;
constexpr float kCoreClearance = 1.5f; //!< spacings between a core and the nearest joint point
constexpr float kCoreLink = 2.5f;      //!< spacings between two points of one core
constexpr float kReturnLink = 2.0f;    //!< spacings a point set aside may be from the stone point it is given back through

struct NeighbourLists
{
    std::vector<std::uint32_t> index; //!< kNeighbours per point, nearest first (UINT32_MAX: none)
    std::vector<float> distance;
    const std::uint32_t* of(std::size_t i) const { return &index[i * kNeighbours]; }
    const float* distancesOf(std::size_t i) const { return &distance[i * kNeighbours]; }
};

//! Calls visit(i, neighbours) with the `k` nearest points of every point i
//! (itself among them, nearest first), in blocks so that the octree's output
//! for one block is the only temporary.
template <typename Visit>
void forNearest(const octree::Octree& tree, const std::vector<Eigen::Vector3f>& planar, std::size_t k, ProgressTicker& ticker, Visit&& visit)
{
    const int level = tree.levelNearestMeanPopulation(static_cast<double>(k) + 4.0);
    std::vector<octree::Neighbour> found;
    constexpr std::size_t kBlock = std::size_t{1} << 17;
    for (std::size_t first = 0; first < planar.size(); first += kBlock) {
        const std::size_t count = std::min(kBlock, planar.size() - first);
        tree.nearestBatch(planar.data() + first, count, k, level, found);
        for (std::size_t q = 0; q < count; ++q)
            visit(first + q, &found[q * k]);
        ticker.checkCancel();
    }
}

//! Every point's twelve nearest others.
NeighbourLists nearestNeighbours(const octree::Octree& tree, const std::vector<Eigen::Vector3f>& planar, ProgressTicker& ticker)
{
    const std::size_t n = planar.size();
    NeighbourLists lists;
    lists.index.assign(n * kNeighbours, UINT32_MAX);
    lists.distance.assign(n * kNeighbours, std::numeric_limits<float>::infinity());
    forNearest(tree, planar, kNeighbours + 1, ticker, [&](std::size_t self, const octree::Neighbour* found) {
        std::size_t kept = 0;
        for (std::size_t k = 0; k <= kNeighbours && kept < kNeighbours; ++k) {
            const octree::Neighbour& nb = found[k];
            if (nb.index == UINT32_MAX || nb.index == self)
                continue;
            lists.index[self * kNeighbours + kept] = nb.index;
            lists.distance[self * kNeighbours + kept] = std::sqrt(nb.squaredDistance);
            ++kept;
        }
    });
    return lists;
}

//! Groups of `members` linked through the neighbour lists: i and j join
//! when either lists the other within `link` times the larger of their two
//! spacings (union-find: the groups do not depend on the order points are
//! visited in, nor on which of the two lists the other). Each member gets
//! its group's number in `group` (-1 elsewhere), numbered from 0.
void groupsOf(const NeighbourLists& lists, const std::vector<std::uint8_t>& members, const std::vector<float>& spacing, float link,
              std::vector<std::int32_t>& group)
{
    const std::size_t n = members.size();
    std::vector<std::uint32_t> parent(n);
    std::iota(parent.begin(), parent.end(), 0u);
    auto root = [&](std::uint32_t i) {
        while (parent[i] != i)
            i = parent[i] = parent[parent[i]];
        return i;
    };
    for (std::uint32_t i = 0; i < n; ++i) {
        if (!members[i])
            continue;
        for (std::size_t k = 0; k < kNeighbours; ++k) {
            const std::uint32_t j = lists.of(i)[k];
            if (j == UINT32_MAX || !members[j] || lists.distancesOf(i)[k] > link * std::max(spacing[i], spacing[j]))
                continue;
            const std::uint32_t a = root(i), b = root(j);
            if (a != b)
                parent[std::max(a, b)] = std::min(a, b);
        }
    }
    group.assign(n, -1);
    std::vector<std::int32_t> number(n, -1);
    std::int32_t groups = 0;
    for (std::uint32_t i = 0; i < n; ++i)
        if (members[i]) {
            const std::uint32_t r = root(i);
            if (number[r] < 0)
                number[r] = groups++;
            group[i] = number[r];
        }
}

//! Whether point i is on the scan's edge: its twelve nearest neighbours
//! leave an empty sector wider than 120 degrees around it.
bool onEdge(const std::vector<Eigen::Vector3f>& planar, const NeighbourLists& lists, std::size_t i)
{
    float angles[kNeighbours];
    std::size_t count = 0;
    for (std::size_t k = 0; k < kNeighbours; ++k) {
        const std::uint32_t j = lists.of(i)[k];
        if (j == UINT32_MAX)
            continue;
        const Eigen::Vector3f d = planar[j] - planar[i];
        if (d.x() != 0.0f || d.y() != 0.0f)
            angles[count++] = std::atan2(d.y(), d.x());
    }
    if (count < 3)
        return true;
    for (std::size_t k = 1; k < count; ++k) // insertion sort of at most twelve angles
        for (std::size_t m = k; m > 0 && angles[m - 1] > angles[m]; --m)
            std::swap(angles[m - 1], angles[m]);
    float widest = angles[0] + 2.0f * 3.14159265f - angles[count - 1];
    for (std::size_t k = 1; k < count; ++k)
        widest = std::max(widest, angles[k] - angles[k - 1]);
    return widest > 2.0f * 3.14159265f / 3.0f;
}

//! Whether each point lies on a line of parting points: along one of eight
//! directions (22.5 degrees apart), the strip 5 spacings long and one wide
//! centred on the point holds at least `kLineShare` parting points. A joint
//! two or three points wide, seen obliquely, is parting only at some of its
//! points, each gap a bridge; its line still holds most of them, and the
//! gaps' points lie on it too. A dark return or a noisy range on a stone
//! stands alone, or with one more in a strip: no line.
std::vector<std::uint8_t> jointLines(const octree::Octree& tree, const std::vector<Eigen::Vector3f>& planar, const std::vector<std::uint8_t>& parting,
                                     const std::vector<float>& spacing, ProgressTicker& ticker)
{
    constexpr std::size_t kStripNeighbours = 24; // a disc of about 2.8 spacings: the strips' reach of 2.5
    constexpr int kDirections = 8;
    constexpr float kHalfLength = 2.5f, kHalfWidth = 0.5f, kLineShare = 0.45f;
    const std::size_t n = planar.size();
    Eigen::Vector2f direction[kDirections];
    for (int d = 0; d < kDirections; ++d) {
        const float angle = static_cast<float>(d) * 3.14159265f / kDirections;
        direction[d] = Eigen::Vector2f(std::cos(angle), std::sin(angle));
    }
    std::vector<std::uint8_t> onLine(n, 0);
    forNearest(tree, planar, kStripNeighbours + 1, ticker, [&](std::size_t i, const octree::Neighbour* found) {
        const float s = spacing[i];
        if (!(s > 0))
            return;
        for (int d = 0; d < kDirections && !onLine[i]; ++d) {
            int inStrip = 0, partingInStrip = 0;
            for (std::size_t k = 0; k <= kStripNeighbours; ++k) {
                const octree::Neighbour& nb = found[k];
                if (nb.index == UINT32_MAX)
                    continue;
                const Eigen::Vector2f offset = (planar[nb.index] - planar[i]).head<2>();
                const float along = offset.dot(direction[d]);
                const float across = offset.x() * direction[d].y() - offset.y() * direction[d].x();
                if (std::abs(along) <= kHalfLength * s && std::abs(across) <= kHalfWidth * s) {
                    ++inStrip;
                    partingInStrip += parting[nb.index];
                }
            }
            onLine[i] = inStrip >= 3 && static_cast<float>(partingInStrip) >= kLineShare * static_cast<float>(inStrip);
        }
    });
    return onLine;
}

//! Thesis 003's cleaning: a stone point with fewer than
//! `cleaningNeighbours` other stone points within the cleaning radius (by
//! default twice the spacing where it lies, among its twelve nearest; asked
//! for more neighbours than those hold, twice the median spacing, searched).
std::vector<std::uint8_t> isolatedStonePoints(const octree::Octree& tree, const std::vector<Eigen::Vector3f>& planar, const NeighbourLists& lists,
                                              const std::vector<float>& spacing, const std::vector<std::uint8_t>& stoneClass,
                                              const StoneRegionParams& params)
{
    const std::size_t n = planar.size();
    std::vector<std::uint8_t> isolated(n, 0);
    float radius = static_cast<float>(params.cleaningRadius);
    if (radius <= 0 && static_cast<std::size_t>(params.cleaningNeighbours) > kNeighbours) {
        std::vector<float> spacings(spacing);
        std::nth_element(spacings.begin(), spacings.begin() + static_cast<std::ptrdiff_t>(n / 2), spacings.end());
        radius = 2.0f * spacings[n / 2];
    }
    if (radius > 0) {
        tree.withinRadiusBatch(planar.data(), n, radius, [&](std::uint32_t q, const octree::Neighbour* nb, std::size_t count) {
            if (!stoneClass[q])
                return;
            int stones = 0;
            for (std::size_t k = 0; k < count; ++k)
                stones += nb[k].index != q && stoneClass[nb[k].index];
            isolated[q] = stones < params.cleaningNeighbours;
        });
        return isolated;
    }
    for (std::size_t i = 0; i < n; ++i) {
        if (!stoneClass[i])
            continue;
        int stones = 0;
        for (std::size_t k = 0; k < kNeighbours; ++k)
            stones += lists.of(i)[k] != UINT32_MAX && lists.distancesOf(i)[k] <= 2.0f * spacing[i] && stoneClass[lists.of(i)[k]];
        isolated[i] = stones < params.cleaningNeighbours;
    }
    return isolated;
}

//! The stone points that are not cores take the group of the nearest core,
//! the distance walked through stone points (Dijkstra over the neighbour
//! lists, steps of at most kReturnLink spacings); those no core reaches keep -1.
void giveBackToCores(const NeighbourLists& lists, const std::vector<std::uint8_t>& stone, const std::vector<std::uint8_t>& core,
                     const std::vector<float>& spacing, std::vector<std::int32_t>& group)
{
    const std::size_t n = stone.size();
    using Reach = std::pair<float, std::uint32_t>;
    std::priority_queue<Reach, std::vector<Reach>, std::greater<Reach>> front;
    std::vector<float> reached(n, std::numeric_limits<float>::infinity());
    for (std::uint32_t i = 0; i < n; ++i)
        if (core[i]) {
            reached[i] = 0.0f;
            front.push({0.0f, i});
        }
    while (!front.empty()) {
        const auto [distance, at] = front.top();
        front.pop();
        if (distance > reached[at])
            continue;
        for (std::size_t k = 0; k < kNeighbours; ++k) {
            const std::uint32_t j = lists.of(at)[k];
            const float step = lists.distancesOf(at)[k];
            if (j == UINT32_MAX || !stone[j] || core[j] || step > kReturnLink * std::max(spacing[at], spacing[j]))
                continue;
            if (distance + step < reached[j]) {
                reached[j] = distance + step;
                group[j] = group[at];
                front.push({reached[j], j});
            }
        }
    }
}

} // namespace

StoneRegions separateStones(const octree::Octree& tree, const std::vector<Eigen::Vector3f>& planar, const std::vector<std::uint8_t>& stoneClass,
                            const std::vector<std::uint8_t>& known, const std::vector<std::uint8_t>& recessed, const StoneRegionParams& params,
                            ProgressTicker& ticker)
{
    const std::size_t n = planar.size();
    StoneRegions out;
    const NeighbourLists lists = nearestNeighbours(tree, planar, ticker);
    out.spacing.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const float eighth = lists.distancesOf(i)[7];
        out.spacing[i] = std::isfinite(eighth) ? eighth / std::sqrt(2.0f) : 0.0f;
    }

    // 1. Isolated stone points are joint points (thesis 003's cleaning).
    std::vector<std::uint8_t> stone = stoneClass;
    const std::vector<std::uint8_t> isolated = isolatedStonePoints(tree, planar, lists, out.spacing, stoneClass, params);
    for (std::size_t i = 0; i < n; ++i)
        if (isolated[i]) {
            stone[i] = 0;
            ++out.isolatedRemoved;
        }

    // 2. The joints' points: where the points that part stones (joint class,
    // or set back from the faces) line up.
    std::vector<std::uint8_t> parting(n, 0);
    for (std::size_t i = 0; i < n; ++i)
        parting[i] = (!stone[i] && known[i]) || (!recessed.empty() && recessed[i]);
    std::vector<std::uint8_t> joint = jointLines(tree, planar, parting, out.spacing, ticker);
    // The scan's edges part too: a joint line that stops a row or two short
    // of the wall's edge, or of a hole (the shadow of a groove seen
    // obliquely), leaves a passage between two stones' cores there.
    for (std::size_t i = 0; i < n; ++i)
        if (!joint[i] && onEdge(planar, lists, i))
            joint[i] = 1;

    // 3. Cores: stone points clear of every joint point by 1.5 spacings, grouped.
    std::vector<std::uint8_t> core(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        if (!stone[i] || joint[i])
            continue;
        bool clear = true;
        for (std::size_t k = 0; k < kNeighbours && clear; ++k) {
            const std::uint32_t j = lists.of(i)[k];
            clear = j == UINT32_MAX || !joint[j] || lists.distancesOf(i)[k] > kCoreClearance * out.spacing[i];
        }
        core[i] = clear;
    }
    ticker.checkCancel();
    std::vector<std::int32_t> group;
    groupsOf(lists, core, out.spacing, kCoreLink, group);

    // 4. The stone points set aside go to the nearest core, through stone points.
    giveBackToCores(lists, stone, core, out.spacing, group);
    for (std::size_t i = 0; i < n; ++i)
        out.setAside += stone[i] && !core[i] && group[i] >= 0;
    out.label = std::move(group);
    out.joint = std::move(joint);
    out.parting = std::move(parting);
    return out;
}

} // namespace scandiff::plugins
