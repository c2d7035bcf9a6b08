// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/processing/LocalFeatures.h>

#include "distance/LocalModels.h"
#include "processing/LocalPlane.h"
#include "processing/PointNeighbourhoods.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>

#include <tbb/enumerable_thread_specific.h>

#include <cmath>
#include <limits>

namespace scandiff {

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Scratch
{
    std::vector<Eigen::Vector3d> points; //!< offsets from the point, which comes first
    detail::ModelScratch model;
};

} // namespace

FeatureResult computeLocalFeatures(const PointCloud& cloud, const FeatureParams& params, ProgressObserver* progress)
{
    if (!(params.radius > 0) || !std::isfinite(params.radius))
        throw Error(ErrorCode::InvalidArgument, "features: the radius must be > 0");
    if (cloud.empty())
        throw Error(ErrorCode::InvalidData, "features: cloud '" + cloud.name + "' is empty");
    const bool all = !params.density && !params.roughness && !params.curvature && !params.verticality;
    const bool density = all || params.density, roughness = all || params.roughness, curvature = all || params.curvature,
               verticality = all || params.verticality;
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    const std::size_t n = cloud.size();
    const auto& positions = cloud.positions();
    const double r = params.radius;

    FeatureResult result;
    const auto addField = [&](const char* name) -> std::vector<float>& {
        result.fields.emplace_back(name, n);
        return result.fields.back().values();
    };
    const char* densityName = params.densityKind == DensityKind::Count     ? fields::kNeighbourCount
                              : params.densityKind == DensityKind::Surface ? fields::kSurfaceDensity
                                                                           : fields::kVolumeDensity;
    const double densityScale = params.densityKind == DensityKind::Count     ? 1.0
                                : params.densityKind == DensityKind::Surface ? 1.0 / (kPi * r * r)
                                                                             : 1.0 / (4.0 / 3.0 * kPi * r * r * r);
    // References into result.fields stay valid: every field is added before any is used.
    result.fields.reserve(5);
    std::vector<float>* densityValues = density ? &addField(densityName) : nullptr;
    std::vector<float>* roughnessValues = roughness ? &addField(fields::kRoughness) : nullptr;
    std::vector<float>* meanValues = curvature ? &addField(fields::kMeanCurvature) : nullptr;
    std::vector<float>* gaussianValues = curvature ? &addField(fields::kGaussianCurvature) : nullptr;
    std::vector<float>* verticalityValues = verticality ? &addField(fields::kVerticality) : nullptr;

    tbb::enumerable_thread_specific<Scratch> scratch;
    ProgressTicker ticker(progress, "Local features", n);
    if (!curvature) {
        // Density, roughness and verticality need only the neighbourhood's moments.
        detail::forEachPointMoments(tree, r, ticker, [&](std::size_t i, const octree::NeighbourhoodMoments& moments) {
            if (densityValues)
                (*densityValues)[i] = static_cast<float>(static_cast<double>(moments.count) * densityScale);
            detail::LocalPlane plane;
            // Roughness: the plane of the neighbours alone, and the point's distance to it.
            if (roughnessValues && detail::fitLocalPlane(moments, true, plane))
                (*roughnessValues)[i] = static_cast<float>(std::abs(plane.mean.dot(plane.normal)));
            if (verticalityValues && detail::fitLocalPlane(moments, false, plane))
                (*verticalityValues)[i] = static_cast<float>(1.0 - std::min(1.0, std::abs(plane.normal.z())));
        });
        return result;
    }
    detail::forEachPointNeighbourhood(tree, r, 0, ticker, [&](std::size_t i, const octree::Neighbour* list, std::size_t count) {
        if (densityValues)
            (*densityValues)[i] = static_cast<float>(static_cast<double>(count) * densityScale);
        if (!roughnessValues && !meanValues && !verticalityValues)
            return;
        Scratch& s = scratch.local();
        const Eigen::Vector3f& p = positions[i];
        s.points.clear();
        s.points.emplace_back(Eigen::Vector3d::Zero());
        for (std::size_t j = 0; j < count; ++j)
            if (list[j].index != i)
                s.points.push_back((positions[list[j].index] - p).cast<double>());
        detail::LocalPlane plane;
        // Roughness: the plane of the neighbours alone, and the point's distance to it.
        if (roughnessValues && detail::fitLocalPlane(s.points, 1, plane))
            (*roughnessValues)[i] = static_cast<float>(std::abs(plane.mean.dot(plane.normal)));
        if (verticalityValues && detail::fitLocalPlane(s.points, 0, plane))
            (*verticalityValues)[i] = static_cast<float>(1.0 - std::min(1.0, std::abs(plane.normal.z())));
        if (meanValues) {
            const Eigen::Vector3d side = cloud.hasNormals() && cloud.normals()[i] != Eigen::Vector3f::Zero()
                                             ? Eigen::Vector3d(cloud.normals()[i].cast<double>())
                                             : Eigen::Vector3d(Eigen::Vector3d::UnitZ());
            detail::FittedModel fitted;
            if (!detail::fitModel(LocalModel::Quadric, s.points, side, fitted, s.model))
                return;
            // Derivatives of the height over the plane at the point; the fit
            // works in coordinates divided by the extent e, so first
            // derivatives need no change and second ones are divided by e.
            const detail::PlaneFrame& f = fitted.frame;
            const Eigen::Matrix<double, 6, 1>& c = fitted.quadric;
            const double e = fitted.extent;
            const double u = -f.centroid.dot(f.u) / e, v = -f.centroid.dot(f.v) / e;
            const double hu = 2 * c[0] * u + c[1] * v + c[3], hv = c[1] * u + 2 * c[2] * v + c[4];
            const double huu = 2 * c[0] / e, huv = c[1] / e, hvv = 2 * c[2] / e;
            const double g = 1 + hu * hu + hv * hv;
            (*gaussianValues)[i] = static_cast<float>((huu * hvv - huv * huv) / (g * g));
            (*meanValues)[i] = static_cast<float>(((1 + hv * hv) * huu - 2 * hu * hv * huv + (1 + hu * hu) * hvv) / (2 * std::pow(g, 1.5)));
        }
    });
    return result;
}

} // namespace scandiff
