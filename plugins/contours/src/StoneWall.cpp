// SPDX-License-Identifier: GPL-3.0-or-later
// The stone-wall workflow of thesis 003 (its retained procedure, §IV.2):
// threshold, classify, clean, contour, in the wall's plane.
#include <scandiff/plugins/contours/StoneWall.h>
#include <scandiff/plugins/contours/PolygonMeasures.h>
#include <scandiff/plugins/contours/Vectorisation.h>

#include "StoneEvidence.h"
#include "StoneRegions.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/geometry/PlanarRings.h>
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

namespace {

//! Step 1: the points' stone or joint class, by the thesis's threshold alone
//! or by the local levels of intensity and relief.
StoneEvidence classifyPoints(const std::vector<Eigen::Vector2d>& uv, const std::vector<double>& height, const std::vector<float>& intensity,
                             double spacing, const StoneParams& params, ProgressTicker& ticker)
{
    StoneEvidenceParams evidence;
    evidence.polarity = params.polarity;
    evidence.threshold = params.threshold;
    evidence.localLevels = params.localLevels;
    evidence.relief = params.relief;
    evidence.window = params.window;
    return classifyStonePoints(uv, height, intensity, spacing, evidence, ticker);
}

//! The grow method's tolerance: the one given, else the stone class's variance.
double growTolerance(const StoneParams& params, const std::vector<float>& intensity, const std::vector<std::uint8_t>& stoneClass)
{
    if (params.growVariance > 0)
        return params.growVariance;
    RunningMoments stones;
    for (std::size_t i = 0; i < intensity.size(); ++i)
        if (stoneClass[i])
            stones.add(intensity[i]);
    if (stones.count < 3)
        throw Error(ErrorCode::InvalidData, "stones: fewer than 3 points on the stone side of the threshold");
    const double tau = stones.variance();
    return tau > 0 ? tau : 1e-12;
}

//! The smallest stone by default: 25 squared spacings (a patch of five by
//! five points), or a twentieth of the median part above that, whichever is
//! larger: where a joint is wide or faint, a few of its points classified
//! stone make a sliver along it, and a wall's stones rarely differ twentyfold.
double automaticMinimumArea(const OutlineResult& parts, double spacing)
{
    const double floor = 25.0 * spacing * spacing;
    std::vector<double> areas;
    for (const OutlinePart& part : parts.parts) {
        const double area = signedArea(part.outer);
        if (area >= floor)
            areas.push_back(area);
    }
    if (areas.empty())
        return floor;
    std::nth_element(areas.begin(), areas.begin() + static_cast<std::ptrdiff_t>(areas.size() / 2), areas.end());
    return std::max(floor, areas[areas.size() / 2] / 20.0);
}

//! Step 4: a stone per accepted part, its outline vectorised at the spacing
//! where it lies, its points and plane residual counted.
void drawStones(const OutlineResult& parts, const std::vector<std::size_t>& accepted, const std::vector<Eigen::Vector2d>& centre,
                const std::vector<std::uint32_t>& kept, const std::vector<float>& localSpacing, const std::vector<Eigen::Vector3d>& global,
                const StoneParams& params, StoneWallResult& result)
{
    std::vector<std::int32_t> stoneOfPart(parts.parts.size(), -1);
    std::vector<std::vector<float>> spacings(parts.parts.size());
    for (std::size_t k = 0; k < kept.size(); ++k)
        if (parts.partOfPoint[k] >= 0)
            spacings[static_cast<std::size_t>(parts.partOfPoint[k])].push_back(localSpacing[kept[k]]);
    for (std::size_t p : accepted) {
        const OutlinePart& part = parts.parts[p];
        Stone stone;
        stone.outline2d = part.outer;
        if (params.vectorise) {
            std::vector<float>& s = spacings[p];
            double spacing = result.spacing;
            if (!s.empty()) {
                std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(s.size() / 2), s.end());
                spacing = std::max(static_cast<double>(s[s.size() / 2]), 1e-9);
            }
            VectoriseParams vector;
            vector.tolerance = 1.5 * spacing;
            vector.edgeOffset = 0.5 * spacing;
            vector.arcs = false; // a stone's sides are straight: its rounded corners are the outline's, not the stone's
            Ring2d drawn = vectoriseRing(part.outer, vector).vertices;
            // A bow-tie is no stone: where the pieces' corners cross, the ring as scanned is kept.
            if (drawn.size() >= 3 && std::abs(signedArea(drawn)) > 0.5 * std::abs(signedArea(part.outer)) && !crossesItself(drawn))
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
    result.stoneOfPoint.assign(global.size(), -1);
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
}

} // namespace

StoneWallResult extractStones(const PointCloud& cloud, const StoneParams& params, ProgressObserver* progress)
{
    const ScalarField* field = cloud.field(params.field);
    if (!field)
        throw Error(ErrorCode::InvalidArgument, "stones: the cloud has no field '" + params.field + "'");
    if (params.cleaningRadius < 0 || params.alpha < 0 || params.minStoneArea < 0 || params.growRadius < 0 || params.growVariance < 0 ||
        params.cleaningNeighbours < 0 || !(params.window >= 0))
        throw Error(ErrorCode::InvalidArgument, "stones: radii, areas, windows, tolerances and counts must be >= 0");
    const std::size_t n = cloud.size();
    if (n < 3)
        throw Error(ErrorCode::InvalidData, "stones: the wall has " + std::to_string(n) + " points, at least 3 are needed");
    std::vector<float> intensity(n); // absolute values (a field may store them around an offset)
    std::vector<std::uint8_t> known(n);
    for (std::size_t i = 0; i < n; ++i) {
        intensity[i] = static_cast<float>(field->value(i));
        known[i] = std::isfinite(intensity[i]);
    }
    ProgressTicker ticker(progress, "Stones", 4 * n);

    StoneWallResult result;
    std::vector<Eigen::Vector3d> global(n);
    for (std::size_t i = 0; i < n; ++i)
        global[i] = cloud.globalPosition(i);
    result.wall = fitPlaneFrame(global);
    std::vector<Eigen::Vector2d> uv(n);
    std::vector<double> height(n);
    for (std::size_t i = 0; i < n; ++i) {
        uv[i] = result.wall.toPlane(global[i]);
        height[i] = (global[i] - result.wall.origin).dot(result.wall.normal);
    }
    const std::vector<Eigen::Vector3f> planar = planarPoints(uv);
    const octree::Octree tree(planar.data(), n);
    result.spacing = medianSpacing(tree, planar);
    ticker.checkCancel();

    // 1. Stone or joint, point by point (thesis 003 §II.1.3, with local levels and relief).
    const StoneEvidence evidence = classifyPoints(uv, height, intensity, result.spacing, params, ticker);
    result.threshold = evidence.threshold;
    result.thresholdIterations = evidence.thresholdIterations;
    result.polarity = evidence.polarity;
    result.stoneMean = evidence.stoneMean;
    result.jointMean = evidence.jointMean;
    result.jointOffset = evidence.jointOffset;
    result.reliefNoise = evidence.reliefNoise;
    result.reliefUsed = evidence.reliefUsed;
    result.classificationRounds = evidence.iterations;
    result.stoneClass = evidence.stone;

    // 2. Stone points grouped stone by stone: cleaned and split where a joint
    // is bridged, or regions grown on intensity.
    StoneRegionParams regionParams;
    regionParams.cleaningRadius = params.cleaningRadius;
    regionParams.cleaningNeighbours = params.cleaningNeighbours;
    StoneRegions regions = separateStones(tree, planar, result.stoneClass, known, evidence.recessed, regionParams, ticker);
    if (params.method == StoneMethod::Classify) { // grow keeps only the spacings of this step
        result.isolatedRemoved = regions.isolatedRemoved;
        result.pointsNearJoints = regions.setAside;
    }
    result.partingPoint = std::move(regions.parting);
    result.jointLine = std::move(regions.joint);
    std::vector<std::int32_t> labels = std::move(regions.label);
    if (params.method == StoneMethod::Grow)
        labels = growOnIntensity(tree, planar, intensity, result.stoneClass,
                                 params.growRadius > 0 ? params.growRadius : 2.0 * result.spacing,
                                 growTolerance(params, intensity, result.stoneClass), ticker);
    ticker.step(n);

    // 3. Contours: a part per stone, from the triangles joining its own points
    // (the longest edge relative to the spacing where it lies, or the alpha radius given).
    std::vector<std::uint32_t> kept;
    std::vector<Eigen::Vector2d> stoneUv;
    OutlineParams outline;
    outline.method = params.alpha > 0 ? OutlineMethod::Alpha : OutlineMethod::LongEdges;
    outline.threshold = params.alpha;
    for (std::uint32_t i = 0; i < n; ++i)
        if (labels[i] >= 0) {
            kept.push_back(i);
            stoneUv.push_back(uv[i]);
            outline.labels.push_back(labels[i]);
        }
    const OutlineResult parts = extractOutlines(stoneUv, outline);
    result.alpha = parts.threshold;
    ticker.checkCancel();

    // 4. Small and nested contours dropped, the others in reading order, drawn.
    const double minArea = params.minStoneArea > 0 ? params.minStoneArea : automaticMinimumArea(parts, result.spacing);
    std::vector<Eigen::Vector2d> centre;
    const std::vector<std::size_t> accepted = selectStones(parts, minArea, result, centre);
    drawStones(parts, accepted, centre, kept, regions.spacing, global, params, result);
    ticker.step(n);
    return result;
}

} // namespace scandiff::plugins
