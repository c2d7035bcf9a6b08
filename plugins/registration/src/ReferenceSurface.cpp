// SPDX-License-Identifier: GPL-3.0-or-later
#include "ReferenceSurface.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToMesh.h>
#include <scandiff/core/geometry/PointTriangleDistance.h>
#include <scandiff/core/processing/Normals.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>

namespace scandiff::plugins::detail {

namespace {

Eigen::Vector3d boxCentre(const PointCloud& cloud)
{
    const BoundingBox box = cloud.bounds();
    return box.empty ? cloud.origin() : Eigen::Vector3d((box.min + box.max) / 2);
}

class CloudSurface : public ReferenceSurface
{
public:
    CloudSurface(const PointCloud& cloud, bool needNormals, std::size_t normalNeighbours, const ProgressObserver* cancel)
        : cloud_(cloud), tree_(buildOctree(cloud, std::nullopt, cancel))
    {
        origin_ = boxCentre(cloud);
        // The cloud's frame relative to ours: a query q (our frame) is the
        // point O + q, that is (O - cloud origin) + q in the cloud's frame.
        shift_ = origin_ - cloud.origin();
        level_ = tree_.levelNearestMeanPopulation(30.0);
        // Normals are fitted where closest points land, when they first do:
        // a registration touches a part of the reference (a sample, its
        // overlap), not all of it.
        if (needNormals && !cloud.hasNormals()) {
            normals_.assign(cloud.size(), Eigen::Vector3f::Zero());
            spread_.assign(cloud.size(), 0.0f);
            fitted_.assign(cloud.size(), 0);
            normalNeighbours_ = normalNeighbours;
        }
    }

    void closest(const std::vector<Eigen::Vector3d>& queries, ClosestPoints& out, double maxDistance) const override
    {
        const std::size_t n = queries.size();
        queries_.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            queries_[i] = (queries[i] + shift_).cast<float>();
        // Slightly wider in float, so a point at the bound in double is not lost to rounding.
        const float bound = std::isfinite(maxDistance) ? static_cast<float>(maxDistance * (1 + 1e-6)) + 1e-6f
                                                       : std::numeric_limits<float>::infinity();
        tree_.nearestBatch(queries_.data(), n, 1, level_, neighbours_, nullptr, bound);
        if (!fitted_.empty()) {
            std::vector<std::uint32_t> missing;
            for (const auto& neighbour : neighbours_)
                if (neighbour.index != std::numeric_limits<std::uint32_t>::max() && !fitted_[neighbour.index]) {
                    fitted_[neighbour.index] = 1;
                    missing.push_back(neighbour.index);
                }
            planeNormalsOf(cloud_, tree_, missing, normalNeighbours_, normals_, &spread_);
        }
        out.points.resize(n);
        out.normals.resize(n);
        out.found.resize(n);
        out.spread.resize(spread_.empty() ? 0 : n);
        const std::vector<Eigen::Vector3f>& normals = cloud_.hasNormals() ? cloud_.normals() : normals_;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const std::uint32_t j = neighbours_[i].index;
                out.found[i] = j != std::numeric_limits<std::uint32_t>::max();
                if (!out.found[i])
                    continue;
                out.points[i] = cloud_.positions()[j].cast<double>() - shift_;
                out.normals[i] = normals.empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(normals[j].cast<double>());
                if (!spread_.empty())
                    out.spread[i] = spread_[j];
            }
        });
    }

private:
    const PointCloud& cloud_;
    octree::Octree tree_;
    int level_ = 1;
    Eigen::Vector3d shift_;
    // Normals fitted so far (zero where not yet, or where no plane fits).
    mutable std::vector<Eigen::Vector3f> normals_;
    mutable std::vector<float> spread_; // the fitted planes' RMS spread, with the normals
    mutable std::vector<char> fitted_;
    std::size_t normalNeighbours_ = 12;
    // Buffers reused from one iteration to the next (a surface serves one run at a time).
    mutable std::vector<Eigen::Vector3f> queries_;
    mutable std::vector<octree::Neighbour> neighbours_;
};

class MeshSurface : public ReferenceSurface
{
public:
    explicit MeshSurface(const Mesh& mesh) : mesh_(mesh)
    {
        mesh.checkConsistency();
        if (mesh.triangles.empty())
            throw Error(ErrorCode::InvalidData, "registration: mesh '" + mesh.name + "' has no triangle");
        origin_ = boxCentre(mesh.vertices);
        shift_ = origin_ - mesh.vertices.origin();
        queries_.setOrigin(mesh.vertices.origin());
    }

    void closest(const std::vector<Eigen::Vector3d>& queries, ClosestPoints& out, double maxDistance) const override
    {
        const std::size_t n = queries.size();
        queries_.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            queries_.positions()[i] = (queries[i] + shift_).cast<float>();
        CloudToMeshParams params;
        params.closestTriangles = true;
        if (std::isfinite(maxDistance) && maxDistance > 0)
            params.maxDistance = maxDistance * (1 + 1e-6) + 1e-6;
        const CloudToMeshResult result = cloudToMesh(queries_, mesh_, params);
        out.points.resize(n);
        out.normals.resize(n);
        out.found.resize(n);
        out.spread.clear();
        const auto& v = mesh_.vertices.positions();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const std::uint32_t t = result.closestTriangle[i];
                out.found[i] = t != kNoClosestTriangle;
                if (!out.found[i])
                    continue;
                const auto& tri = mesh_.triangles[t];
                const Eigen::Vector3d a = v[tri[0]].cast<double>(), b = v[tri[1]].cast<double>(), c = v[tri[2]].cast<double>();
                // The exact closest point, on the triangle the search kept.
                const geometry::PointTriangleResult closest = geometry::pointTriangleDistance(queries[i] + shift_, a, b, c);
                out.points[i] = closest.closestPoint - shift_;
                const Eigen::Vector3d normal = (b - a).cross(c - a);
                const double length = normal.norm();
                out.normals[i] = length > 0 ? Eigen::Vector3d(normal / length) : Eigen::Vector3d::Zero();
            }
        });
    }

private:
    const Mesh& mesh_;
    Eigen::Vector3d shift_;
    mutable PointCloud queries_;
};

} // namespace

std::unique_ptr<ReferenceSurface> cloudSurface(const PointCloud& cloud, bool needNormals, std::size_t normalNeighbours,
                                               const ProgressObserver* cancel)
{
    return std::make_unique<CloudSurface>(cloud, needNormals, normalNeighbours, cancel);
}

std::unique_ptr<ReferenceSurface> meshSurface(const Mesh& mesh)
{
    return std::make_unique<MeshSurface>(mesh);
}

} // namespace scandiff::plugins::detail
