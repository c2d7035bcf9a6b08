// SPDX-License-Identifier: GPL-3.0-or-later
// The stone-wall workflow of thesis 003 (its retained procedure, §IV.2):
// threshold, classify, clean, contour, in the wall's plane.
#include <scandiff/plugins/contours/StoneWall.h>
#include <scandiff/plugins/contours/Vectorisation.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/RunningMoments.h>
#include <scandiff/octree/Octree.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <numeric>
#include <random>

namespace scandiff::plugins {

namespace {

//! In-plane coordinates as 3D floats for the octree (z = 0): neighbourhoods
//! are taken in the wall plane, as the thesis projects before contouring.
std::vector<Eigen::Vector3f> planarPoints(const std::vector<Eigen::Vector2d>& uv)
{
    std::vector<Eigen::Vector3f> out(uv.size());
    for (std::size_t i = 0; i < uv.size(); ++i)
        out[i] = Eigen::Vector3f(static_cast<float>(uv[i].x()), static_cast<float>(uv[i].y()), 0.0f);
    return out;
}

double medianSpacing(const octree::Octree& tree, const std::vector<Eigen::Vector3f>& points)
{
    std::vector<octree::Neighbour> neighbours;
    const int level = tree.levelNearestMeanPopulation(8.0);
    tree.nearestBatch(points.data(), points.size(), 2, level, neighbours);
    std::vector<double> nearest;
    nearest.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        if (neighbours[2 * i + 1].index != UINT32_MAX && neighbours[2 * i + 1].squaredDistance > 0)
            nearest.push_back(std::sqrt(static_cast<double>(neighbours[2 * i + 1].squaredDistance)));
    if (nearest.empty())
        throw Error(ErrorCode::InvalidData, "stones: every point of the wall is at the same place");
    std::nth_element(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2), nearest.end());
    return nearest[nearest.size() / 2];
}

//! Thesis 003 §II.2 on intensity, made deterministic and leak-proof: seeds are
//! stone-class points taken in a seeded random order; a seed whose R-disc has
//! an intensity variance above tau is skipped (the thesis draws another); a
//! region grows through R-discs, a point joining while the region's variance
//! with it stays below tau, its intensity lies within 3 sqrt(tau) of the
//! region's mean and on the stone side of the threshold. The last two tests
//! are ours: on a large region one joint point hardly moves the variance,
//! which is how the thesis's regions leaked (8.6 % false stone points on its
//! wall n°1); the thesis constrains only its seeds to the stone side.
std::vector<std::int32_t> growOnIntensity(const octree::Octree& tree, const std::vector<Eigen::Vector3f>& points,
                                          const std::vector<float>& intensity, const std::vector<std::uint8_t>& stoneClass,
                                          double radius, double tau, ProgressTicker& ticker)
{
    const std::size_t n = points.size();
    // Every point's R-disc, once (in parallel), as compressed lists.
    std::vector<std::uint32_t> counts(n + 1, 0);
    std::vector<std::vector<std::uint32_t>> lists(n);
    tree.withinRadiusBatch(points.data(), n, static_cast<float>(radius),
                           [&](std::uint32_t q, const octree::Neighbour* nb, std::size_t count) {
                               auto& list = lists[q];
                               list.reserve(count);
                               for (std::size_t k = 0; k < count; ++k)
                                   if (nb[k].index != q)
                                       list.push_back(nb[k].index);
                               std::sort(list.begin(), list.end());
                           });
    std::vector<std::uint32_t> seeds;
    for (std::uint32_t i = 0; i < n; ++i)
        if (stoneClass[i] && std::isfinite(intensity[i]))
            seeds.push_back(i);
    std::mt19937_64 random(2015);
    std::shuffle(seeds.begin(), seeds.end(), random);
    std::vector<std::int32_t> region(n, -1);
    const double band = 3.0 * std::sqrt(tau);
    std::int32_t next = 0;
    std::deque<std::uint32_t> front;
    for (std::uint32_t seed : seeds) {
        ticker.step();
        if (region[seed] >= 0)
            continue;
        RunningMoments disc;
        disc.add(intensity[seed]);
        for (std::uint32_t j : lists[seed])
            if (region[j] < 0 && std::isfinite(intensity[j]))
                disc.add(intensity[j]);
        if (disc.count < 3 || disc.variance() > tau)
            continue; // not a homogeneous seed surface
        const std::int32_t id = next++;
        RunningMoments stone;
        auto join = [&](std::uint32_t j) {
            region[j] = id;
            stone.add(intensity[j]);
            front.push_back(j);
        };
        join(seed);
        while (!front.empty()) {
            const std::uint32_t at = front.front();
            front.pop_front();
            for (std::uint32_t j : lists[at]) {
                if (region[j] >= 0 || !stoneClass[j])
                    continue;
                const double value = intensity[j];
                if (stone.varianceWith(value) < tau && std::abs(value - stone.mean()) <= band)
                    join(j);
            }
        }
    }
    return region;
}

//! The parts that are stones, in reading order (rows of
//! the wall from the top, left to right): a part smaller than `minArea` is
//! dropped, and so is one inside another's outline (a patch of missed points;
//! a stone has no holes). `centre` gets each part's polygon centroid.
std::vector<std::size_t> selectStones(const OutlineResult& parts, double minArea, StoneWallResult& result, std::vector<Eigen::Vector2d>& centre)
{
    struct Box
    {
        Eigen::Vector2d min, max;
    };
    std::vector<Box> boxes;
    std::vector<std::size_t> accepted; // part indices, largest first
    for (std::size_t p = 0; p < parts.parts.size(); ++p) {
        const Ring2d& ring = parts.parts[p].outer;
        if (signedArea(ring) < minArea) {
            ++result.smallDropped;
            continue;
        }
        Box box{ring.front(), ring.front()};
        for (const Eigen::Vector2d& q : ring) {
            box.min = box.min.cwiseMin(q);
            box.max = box.max.cwiseMax(q);
        }
        bool nested = false;
        for (std::size_t a = 0; a < accepted.size() && !nested; ++a) {
            const Box& other = boxes[a];
            if ((box.min.array() >= other.min.array()).all() && (box.max.array() <= other.max.array()).all())
                nested = containsPoint(parts.parts[accepted[a]].outer, ring[0]); // a vertex of the smaller one
        }
        if (nested) {
            ++result.nestedDropped;
            continue;
        }
        accepted.push_back(p);
        boxes.push_back(box);
    }

    // Stones numbered in reading order: by rows of the wall from the top, then left to right.
    centre.assign(parts.parts.size(), Eigen::Vector2d::Zero());
    for (std::size_t p : accepted) {
        const Ring2d& ring = parts.parts[p].outer;
        Eigen::Vector2d c = Eigen::Vector2d::Zero();
        double twice = 0.0;
        for (std::size_t i = 0; i < ring.size(); ++i) {
            const Eigen::Vector2d a = ring[i] - ring[0], b = ring[(i + 1) % ring.size()] - ring[0];
            const double cross = a.x() * b.y() - b.x() * a.y();
            twice += cross;
            c += cross * (a + b);
        }
        centre[p] = ring[0] + c / (3.0 * twice);
    }
    const double row = std::sqrt(minArea) * 2.0;
    std::sort(accepted.begin(), accepted.end(), [&](std::size_t a, std::size_t b) {
        const double ra = std::floor(-centre[a].y() / row), rb = std::floor(-centre[b].y() / row);
        return ra != rb ? ra < rb : centre[a].x() < centre[b].x();
    });
    return accepted;
}

} // namespace

InterMeansThreshold interMeansThreshold(const std::vector<float>& values, std::optional<double> initial)
{
    std::vector<double> sorted;
    sorted.reserve(values.size());
    for (float v : values)
        if (std::isfinite(v))
            sorted.push_back(v);
    std::sort(sorted.begin(), sorted.end());
    if (sorted.size() < 2 || sorted.front() == sorted.back())
        throw Error(ErrorCode::InvalidData, "inter-means threshold: needs at least two different finite values");
    std::vector<double> prefix(sorted.size() + 1, 0.0); // prefix[k] = sum of the k smallest
    for (std::size_t i = 0; i < sorted.size(); ++i)
        prefix[i + 1] = prefix[i] + sorted[i];
    InterMeansThreshold out;
    double s = initial ? *initial : prefix.back() / static_cast<double>(sorted.size());
    std::size_t previousSplit = SIZE_MAX;
    for (out.iterations = 1; out.iterations <= 10000; ++out.iterations) {
        // The low class holds the values <= S (thesis: S belongs to the lower sum).
        std::size_t split = static_cast<std::size_t>(std::upper_bound(sorted.begin(), sorted.end(), s) - sorted.begin());
        split = std::clamp<std::size_t>(split, 1, sorted.size() - 1); // neither class empty
        out.lowCount = split;
        out.highCount = sorted.size() - split;
        out.lowMean = prefix[split] / static_cast<double>(split);
        out.highMean = (prefix.back() - prefix[split]) / static_cast<double>(out.highCount);
        s = 0.5 * (out.lowMean + out.highMean);
        if (split == previousSplit)
            break; // the classes no longer change: S is a fixed point
        previousSplit = split;
    }
    out.threshold = s;
    return out;
}

StonePolarity parseStonePolarity(const std::string& name)
{
    if (name == "dark")
        return StonePolarity::Dark;
    if (name == "bright")
        return StonePolarity::Bright;
    if (name == "auto")
        return StonePolarity::Auto;
    throw Error(ErrorCode::InvalidArgument, "stones: polarity '" + name + "': expected dark, bright or auto");
}

StoneMethod parseStoneMethod(const std::string& name)
{
    if (name == "classify")
        return StoneMethod::Classify;
    if (name == "grow")
        return StoneMethod::Grow;
    throw Error(ErrorCode::InvalidArgument, "stones: method '" + name + "': expected classify or grow");
}

StoneWallResult extractStones(const PointCloud& cloud, const StoneParams& params, ProgressObserver* progress)
{
    const ScalarField* field = cloud.field(params.field);
    if (!field)
        throw Error(ErrorCode::InvalidArgument, "stones: the cloud has no field '" + params.field + "'");
    if (params.cleaningRadius < 0 || params.alpha < 0 || params.minStoneArea < 0 || params.growRadius < 0 || params.growVariance < 0 ||
        params.cleaningNeighbours < 0)
        throw Error(ErrorCode::InvalidArgument, "stones: radii, areas, tolerances and counts must be >= 0");
    const std::size_t n = cloud.size();
    if (n < 3)
        throw Error(ErrorCode::InvalidData, "stones: the wall has " + std::to_string(n) + " points, at least 3 are needed");
    std::vector<float> intensity(n); // absolute values (a field may store them around an offset)
    for (std::size_t i = 0; i < n; ++i)
        intensity[i] = static_cast<float>(field->value(i));
    ProgressTicker ticker(progress, "Stones", 2 * n);

    StoneWallResult result;
    std::vector<Eigen::Vector3d> global(n);
    for (std::size_t i = 0; i < n; ++i)
        global[i] = cloud.globalPosition(i);
    result.wall = fitPlaneFrame(global);
    std::vector<Eigen::Vector2d> uv(n);
    for (std::size_t i = 0; i < n; ++i)
        uv[i] = result.wall.toPlane(global[i]);
    ticker.checkCancel();

    // 1. Classification by intensity (thesis 003 §II.1.3).
    if (params.threshold) {
        result.threshold = *params.threshold;
    } else {
        const InterMeansThreshold found = interMeansThreshold(intensity);
        result.threshold = found.threshold;
        result.thresholdIterations = found.iterations;
    }
    StonePolarity polarity = params.polarity;
    if (polarity == StonePolarity::Auto) {
        std::size_t below = 0, above = 0;
        for (float v : intensity)
            if (std::isfinite(v))
                (v <= result.threshold ? below : above) += 1;
        polarity = below >= above ? StonePolarity::Dark : StonePolarity::Bright;
    }
    result.polarity = polarity;
    result.stoneClass.assign(n, 0);
    double sums[2] = {0, 0};
    std::size_t counts[2] = {0, 0};
    for (std::size_t i = 0; i < n; ++i) {
        const float v = intensity[i];
        result.stoneClass[i] = std::isfinite(v) && (polarity == StonePolarity::Dark ? v <= result.threshold : v > result.threshold);
        if (std::isfinite(v)) {
            sums[result.stoneClass[i]] += v;
            ++counts[result.stoneClass[i]];
        }
    }
    result.jointMean = counts[0] ? sums[0] / static_cast<double>(counts[0]) : result.threshold;
    result.stoneMean = counts[1] ? sums[1] / static_cast<double>(counts[1]) : result.threshold;

    const std::vector<Eigen::Vector3f> planar = planarPoints(uv);
    const octree::Octree tree(planar.data(), n);
    result.spacing = medianSpacing(tree, planar);
    ticker.checkCancel();

    // 2. Stone points: cleaned classification, or regions grown on intensity.
    std::vector<std::int32_t> labels(n, -1);
    if (params.method == StoneMethod::Classify) {
        const double radius = params.cleaningRadius > 0 ? params.cleaningRadius : 2.0 * result.spacing;
        std::vector<std::uint8_t> isolated(n, 0);
        tree.withinRadiusBatch(planar.data(), n, static_cast<float>(radius),
                               [&](std::uint32_t q, const octree::Neighbour* nb, std::size_t count) {
                                   if (!result.stoneClass[q])
                                       return;
                                   int stones = 0;
                                   for (std::size_t k = 0; k < count; ++k)
                                       stones += nb[k].index != q && result.stoneClass[nb[k].index];
                                   isolated[q] = stones < params.cleaningNeighbours;
                               });
        for (std::size_t i = 0; i < n; ++i) {
            result.isolatedRemoved += isolated[i];
            labels[i] = result.stoneClass[i] && !isolated[i] ? 0 : -1;
        }
        ticker.step(n);
    } else {
        double tau = params.growVariance;
        if (tau <= 0) {
            double sum = 0, sumSquares = 0;
            std::size_t count = 0;
            for (std::size_t i = 0; i < n; ++i)
                if (result.stoneClass[i]) {
                    sum += intensity[i];
                    sumSquares += static_cast<double>(intensity[i]) * intensity[i];
                    ++count;
                }
            if (count < 3)
                throw Error(ErrorCode::InvalidData, "stones: fewer than 3 points on the stone side of the threshold");
            tau = sumSquares / count - (sum / count) * (sum / count);
            if (!(tau > 0))
                tau = 1e-12;
        }
        labels = growOnIntensity(tree, planar, intensity, result.stoneClass,
                                 params.growRadius > 0 ? params.growRadius : 2.0 * result.spacing, tau, ticker);
    }
    ticker.checkCancel();

    // 3. Contours: the alpha shape of the stone points, a part per stone.
    std::vector<std::uint32_t> kept;
    std::vector<Eigen::Vector2d> stoneUv;
    OutlineParams outline;
    outline.method = OutlineMethod::Alpha;
    outline.threshold = params.alpha;
    for (std::uint32_t i = 0; i < n; ++i)
        if (labels[i] >= 0) {
            kept.push_back(i);
            stoneUv.push_back(uv[i]);
            if (params.method == StoneMethod::Grow)
                outline.labels.push_back(labels[i]);
        }
    const OutlineResult parts = extractOutlines(stoneUv, outline);
    result.alpha = parts.threshold;
    ticker.checkCancel();

    // 4. Small and nested contours dropped, the others in reading order.
    const double minArea = params.minStoneArea > 0 ? params.minStoneArea : 100.0 * result.spacing * result.spacing;
    std::vector<Eigen::Vector2d> centre;
    const std::vector<std::size_t> accepted = selectStones(parts, minArea, result, centre);
    std::vector<std::int32_t> stoneOfPart(parts.parts.size(), -1);
    for (std::size_t p : accepted) {
        const OutlinePart& part = parts.parts[p];
        Stone stone;
        stone.outline2d = part.outer;
        if (params.vectorise) {
            VectoriseParams vector;
            vector.tolerance = 1.5 * result.spacing;
            vector.edgeOffset = 0.5 * result.spacing;
            vector.arcs = false; // a stone's sides are straight: its rounded corners are the outline's, not the stone's
            Ring2d drawn = vectoriseRing(part.outer, vector).vertices;
            if (drawn.size() >= 3 && std::abs(signedArea(drawn)) > 0.5 * std::abs(signedArea(part.outer)))
                stone.outline2d = std::move(drawn);
        }
        for (const Eigen::Vector2d& q : stone.outline2d)
            stone.outline.push_back(result.wall.toWorld(q));
        stone.area = signedArea(stone.outline2d);
        stone.perimeter = ringPerimeter(stone.outline2d);
        stone.centroid = result.wall.toWorld(centre[p]);
        stoneOfPart[p] = static_cast<std::int32_t>(result.stones.size());
        result.stones.push_back(std::move(stone));
    }
    result.stoneOfPoint.assign(n, -1);
    std::vector<double> sumSquares(result.stones.size(), 0.0);
    for (std::size_t k = 0; k < kept.size(); ++k) {
        const std::int32_t part = parts.partOfPoint[k];
        if (part < 0 || stoneOfPart[static_cast<std::size_t>(part)] < 0)
            continue;
        const std::int32_t stone = stoneOfPart[static_cast<std::size_t>(part)];
        result.stoneOfPoint[kept[k]] = stone;
        const double d = (global[kept[k]] - result.wall.origin).dot(result.wall.normal);
        sumSquares[static_cast<std::size_t>(stone)] += d * d;
        ++result.stones[static_cast<std::size_t>(stone)].points;
    }
    for (std::size_t s = 0; s < result.stones.size(); ++s)
        result.stones[s].planeRms = result.stones[s].points ? std::sqrt(sumSquares[s] / static_cast<double>(result.stones[s].points)) : 0.0;
    ticker.step(n);
    return result;
}

} // namespace scandiff::plugins
