// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/distance/M3C2.h>

#include "processing/LocalPlane.h"
#include "processing/PointNeighbourhoods.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace scandiff {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
//! Queries per withinRadiusBatch call: bounds the lists held at once.
constexpr std::size_t kQueriesPerBatch = 1 << 16;

void checkParams(const M3c2Params& p)
{
    auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
    if (p.normalScales.empty())
        throw Error(ErrorCode::InvalidArgument, "m3c2: at least one normal scale is needed");
    for (double d : p.normalScales)
        if (!positive(d))
            throw Error(ErrorCode::InvalidArgument, "m3c2: a normal scale must be a positive diameter (m), not " + std::to_string(d));
    if (!positive(p.projectionScale))
        throw Error(ErrorCode::InvalidArgument, "m3c2: the projection scale must be a positive diameter (m)");
    if (!positive(p.maxDepth))
        throw Error(ErrorCode::InvalidArgument, "m3c2: the maximum depth must be positive (m)");
    if (!std::isfinite(p.registrationError) || p.registrationError < 0.0)
        throw Error(ErrorCode::InvalidArgument, "m3c2: the registration error must be zero or positive (m)");
    if (p.minPoints < 1)
        throw Error(ErrorCode::InvalidArgument, "m3c2: the minimum number of points must be at least 1");
}

void checkCloud(const PointCloud& cloud, const char* role)
{
    if (cloud.empty())
        throw Error(ErrorCode::InvalidData, std::string("m3c2: the ") + role + " cloud '" + cloud.name + "' is empty");
}

//! The positions of `cloud` in the frame of `origin`, through double.
std::vector<Eigen::Vector3f> inFrame(const PointCloud& cloud, const Eigen::Vector3d& origin)
{
    std::vector<Eigen::Vector3f> out(cloud.size());
    const Eigen::Vector3d shift = cloud.origin() - origin;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i)
            out[i] = (cloud.positions()[i].cast<double>() + shift).cast<float>();
    });
    return out;
}

//! The normal of every core point: the most planar of the scales. The
//! neighbours are summed in the order of their indices, not in the octree's:
//! a core point's normal then depends only on which reference points lie within
//! the scale, so scandiff-mpi's tiles (a part of the reference, another octree)
//! give it to the bit.
void fitNormals(const octree::Octree& reference, const std::vector<Eigen::Vector3f>& cores, const M3c2Params& params,
                std::vector<Eigen::Vector3d>& normals, std::vector<double>& scales, ProgressObserver* progress)
{
    const std::size_t n = cores.size();
    normals.assign(n, Eigen::Vector3d::Zero());
    scales.assign(n, kNaN);
    std::vector<double> variation(n, std::numeric_limits<double>::infinity());
    ProgressTicker ticker(progress, "M3C2: normals", n * params.normalScales.size());
    const Eigen::Vector3f* points = reference.points();
    tbb::enumerable_thread_specific<std::vector<std::uint32_t>> scratch;
    for (double scale : params.normalScales) {
        for (std::size_t begin = 0; begin < n; begin += kQueriesPerBatch) {
            const std::size_t count = std::min(kQueriesPerBatch, n - begin);
            detail::SparseSteps steps(ticker);
            reference.withinRadiusBatch(
                cores.data() + begin, count, static_cast<float>(scale / 2),
                [&](std::uint32_t q, const octree::Neighbour* list, std::size_t size) {
                    // Per query: Cancel is heard inside a batch, even when a
                    // large scale makes each query long.
                    steps.step();
                    std::vector<std::uint32_t>& indices = scratch.local();
                    indices.resize(size);
                    for (std::size_t k = 0; k < size; ++k)
                        indices[k] = list[k].index;
                    std::sort(indices.begin(), indices.end());
                    const std::size_t i = begin + q;
                    const Eigen::Vector3f& c = cores[i];
                    // The offsets in float, as the octree's moments take them.
                    octree::NeighbourhoodMoments m;
                    for (const std::uint32_t k : indices) {
                        const Eigen::Vector3f d = points[k] - c;
                        m.add(d.cast<double>());
                    }
                    detail::LocalPlane plane;
                    if (!detail::fitLocalPlane(m, false, plane))
                        return;
                    const double v = plane.values[0] / plane.values.sum();
                    if (v < variation[i]) {
                        variation[i] = v;
                        normals[i] = plane.normal;
                        scales[i] = scale;
                    }
                });
            steps.flush();
            ticker.checkCancel();
        }
    }
}

//! Turns each normal to the side the orientation rule gives.
void orient(const PointCloud& reference, const std::vector<Eigen::Vector3f>& cores, const M3c2Params& params,
            std::vector<Eigen::Vector3d>& normals, ProgressObserver* progress)
{
    PointCloud frame;
    frame.setOrigin(reference.origin());
    frame.positions() = cores;
    frame.sensors() = reference.sensors();
    std::vector<Eigen::Vector3f> sides(normals.size());
    for (std::size_t i = 0; i < normals.size(); ++i)
        sides[i] = normals[i].cast<float>();
    if (params.orientation.kind == NormalOrientation::Kind::MinimumSpanningTree ||
        params.orientation.kind == NormalOrientation::Kind::None)
        throw Error(ErrorCode::InvalidArgument, "m3c2: orient the normals by a direction, the sensor or the centroid");
    orientNormals(frame, sides, params.orientation, progress);
    for (std::size_t i = 0; i < normals.size(); ++i)
        if (sides[i].cast<double>().dot(normals[i]) < 0.0)
            normals[i] = -normals[i];
}

//! One epoch's summary inside one cylinder.
struct CylinderStats
{
    std::size_t count = 0;
    double centre = kNaN; //!< mean or median of t
    double spread = kNaN; //!< σ, or IQR / 1.349
};

//! Quantile of sorted values by linear interpolation between order
//! statistics (Hyndman and Fan type 7, as numpy's default).
double quantile(const std::vector<double>& sorted, double q)
{
    const double at = q * static_cast<double>(sorted.size() - 1);
    const auto below = static_cast<std::size_t>(std::floor(at));
    const std::size_t above = std::min(below + 1, sorted.size() - 1);
    return sorted[below] + (at - static_cast<double>(below)) * (sorted[above] - sorted[below]);
}

CylinderStats summarise(std::vector<double>& t, const M3c2Params& params)
{
    CylinderStats s;
    s.count = t.size();
    if (t.empty())
        return s;
    if (params.robust) {
        std::sort(t.begin(), t.end());
        s.centre = quantile(t, 0.5);
        // 1.349 = IQR of the standard normal: the spread is then a σ estimate.
        s.spread = (quantile(t, 0.75) - quantile(t, 0.25)) / 1.349;
        return s;
    }
    double sum = 0.0;
    for (double v : t)
        sum += v;
    const double n = static_cast<double>(t.size());
    s.centre = sum / n;
    double squares = 0.0;
    for (double v : t)
        squares += (v - s.centre) * (v - s.centre);
    s.spread = params.sampleStd ? (t.size() > 1 ? std::sqrt(squares / (n - 1)) : kNaN) : std::sqrt(squares / n);
    return s;
}

//! The cylinder of every core point in one epoch (the octree's cylinder
//! query: the exact test in double, reading only the cells near the axis).
std::vector<CylinderStats> cylinderStats(const octree::Octree& epoch, const std::vector<Eigen::Vector3f>& cores,
                                         const std::vector<Eigen::Vector3d>& normals, const M3c2Params& params,
                                         const std::string& stage, ProgressObserver* progress)
{
    const std::size_t n = cores.size();
    std::vector<CylinderStats> stats(n);
    std::vector<octree::Octree::CylinderQuery> cylinders(std::min(kQueriesPerBatch, n));
    tbb::enumerable_thread_specific<std::vector<double>> positions;
    tbb::enumerable_thread_specific<std::vector<std::pair<std::uint32_t, double>>> pairs;
    ProgressTicker ticker(progress, stage, n);
    for (std::size_t begin = 0; begin < n; begin += kQueriesPerBatch) {
        const std::size_t count = std::min(kQueriesPerBatch, n - begin);
        for (std::size_t j = 0; j < count; ++j) {
            octree::Octree::CylinderQuery& cylinder = cylinders[j];
            cylinder.centre = cores[begin + j].cast<double>();
            // A core point without a normal gets no query (a zero axis).
            cylinder.axis = normals[begin + j];
            cylinder.radius = params.projectionScale / 2;
            cylinder.halfLength = params.maxDepth;
        }
        detail::SparseSteps steps(ticker);
        epoch.withinCylinderBatch(cylinders.data(), count,
                                  [&](std::uint32_t q, const std::uint32_t* indices, const double* along, std::size_t size) {
                                      steps.step();
                                      // In the order of the points' indices (see fitNormals).
                                      std::vector<std::pair<std::uint32_t, double>>& byIndex = pairs.local();
                                      byIndex.resize(size);
                                      for (std::size_t k = 0; k < size; ++k)
                                          byIndex[k] = {indices[k], along[k]};
                                      std::sort(byIndex.begin(), byIndex.end());
                                      std::vector<double>& t = positions.local();
                                      t.resize(size);
                                      for (std::size_t k = 0; k < size; ++k)
                                          t[k] = byIndex[k].second;
                                      stats[begin + q] = summarise(t, params);
                                  });
        steps.flush();
        ticker.checkCancel();
    }
    return stats;
}

//! What m3c2 and m3c2OnParts share once their inputs are checked.
M3c2Result m3c2Measure(const PointCloud& reference, const PointCloud& compared, const PointCloud& corePoints,
                       const M3c2Params& params, ProgressObserver* progress)
{
    const Eigen::Vector3d origin = reference.origin();
    const std::vector<Eigen::Vector3f> cores = inFrame(corePoints, origin);
    for (const Eigen::Vector3f& c : cores)
        if (!c.allFinite())
            throw Error(ErrorCode::InvalidData, "m3c2: the core points of '" + corePoints.name + "' include a non-finite one");
    // One epoch's octree at a time: the reference's is gone before the
    // compared one is built (the peak holds one).
    // An empty epoch (a part of one, m3c2OnParts) gives no normal, empty cylinders.
    std::vector<Eigen::Vector3d> normals(cores.size(), Eigen::Vector3d::Zero());
    std::vector<double> scales(cores.size(), kNaN);
    std::vector<CylinderStats> first(cores.size()), second(cores.size());
    if (!reference.empty()) {
        const octree::Octree referenceTree = buildOctree(reference, std::nullopt, progress);
        fitNormals(referenceTree, cores, params, normals, scales, progress);
        orient(reference, cores, params, normals, progress);
        first = cylinderStats(referenceTree, cores, normals, params, "M3C2: reference cylinders", progress);
    } else {
        orient(reference, cores, params, normals, progress); // its errors all the same
    }
    if (!compared.empty()) {
        PointCloud shifted;
        shifted.name = compared.name;
        shifted.positions() = inFrame(compared, origin);
        const octree::Octree comparedTree = buildOctree(shifted, std::nullopt, progress);
        second = cylinderStats(comparedTree, cores, normals, params, "M3C2: compared cylinders", progress);
    }

    M3c2Result result;
    result.corePoints = corePoints.clone();
    PointCloud& out = result.corePoints;
    if (out.crsWkt().empty())
        out.setCrsWkt(reference.crsWkt());
    const std::size_t n = cores.size();
    std::vector<Eigen::Vector3f>& outNormals = out.enableNormals();
    const char* names[] = {fields::kM3c2Distance, fields::kM3c2Uncertainty, fields::kM3c2Significant,
                           fields::kM3c2N1,       fields::kM3c2N2,          fields::kM3c2Std1,
                           fields::kM3c2Std2,     fields::kM3c2NormalScale};
    for (const char* name : names)
        out.addField(ScalarField(name, n));
    // Pointers once every field exists: adding one may move the others.
    ScalarField* f[8];
    for (int k = 0; k < 8; ++k)
        f[k] = out.field(names[k]);
    for (std::size_t i = 0; i < n; ++i) {
        outNormals[i] = normals[i].cast<float>();
        if (normals[i].isZero()) {
            ++result.withoutNormal;
            continue;
        }
        const CylinderStats& a = first[i];
        const CylinderStats& b = second[i];
        f[3]->setValue(i, static_cast<double>(a.count));
        f[4]->setValue(i, static_cast<double>(b.count));
        f[5]->setValue(i, a.spread);
        f[6]->setValue(i, b.spread);
        f[7]->setValue(i, scales[i]);
        if (a.count == 0 || b.count == 0)
            continue;
        const double distance = b.centre - a.centre;
        f[0]->setValue(i, distance);
        ++result.measuredCount;
        if (a.count < params.minPoints || b.count < params.minPoints)
            continue;
        const double lod = 1.96 * (std::sqrt(a.spread * a.spread / static_cast<double>(a.count) +
                                             b.spread * b.spread / static_cast<double>(b.count)) +
                                   params.registrationError);
        f[1]->setValue(i, lod);
        if (std::isnan(lod))
            continue;
        const bool significant = std::abs(distance) > lod;
        f[2]->setValue(i, significant ? 1.0 : 0.0);
        result.significantCount += significant ? 1 : 0;
    }
    return result;
}

} // namespace

M3c2Result m3c2(const PointCloud& reference, const PointCloud& compared, const PointCloud& corePoints, const M3c2Params& params,
                ProgressObserver* progress)
{
    checkParams(params);
    checkCloud(reference, "reference");
    checkCloud(compared, "compared");
    return m3c2Measure(reference, compared, corePoints, params, progress);
}

M3c2Result m3c2OnParts(const PointCloud& reference, const PointCloud& compared, const PointCloud& corePoints,
                       const M3c2Params& params, ProgressObserver* progress)
{
    checkParams(params);
    return m3c2Measure(reference, compared, corePoints, params, progress);
}

} // namespace scandiff
