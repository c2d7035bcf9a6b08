// SPDX-License-Identifier: GPL-3.0-or-later
#include "PlanarPolygons.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/distance/M3C2.h>
#include <scandiff/core/segmentation/RegionReport.h>
#include <scandiff/octree/Octree.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

namespace scandiff {

namespace {

//! The 2.5D volume between the epochs inside the region's footprint (see RegionStatistics::volume).
void measureVolume(const PointCloud& cloud, const std::vector<std::size_t>& indices, const PointCloud& other,
                   const RegionReportParams& params, double c, RegionStatistics& r, const ProgressTicker* ticker)
{
    // Columns on a horizontal grid anchored at the footprint's box (global X, Y).
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Polygon2d& ring : r.footprint)
        for (const Eigen::Vector2d& q : ring) {
            lo = lo.cwiseMin(q);
            hi = hi.cwiseMax(q);
        }
    if (!(lo.x() <= hi.x()))
        return;
    const double nxd = std::floor((hi.x() - lo.x()) / c) + 1, nyd = std::floor((hi.y() - lo.y()) / c) + 1;
    if (nxd * nyd > 1e8)
        throw Error(ErrorCode::InvalidArgument, "region report: the volume cell size " + std::to_string(c) +
                                                    " m is too small for region " + std::to_string(r.id));
    const auto nx = static_cast<std::int64_t>(nxd);
    auto columnOf = [&](const Eigen::Vector3d& g) -> std::int64_t {
        const double fx = std::floor((g.x() - lo.x()) / c), fy = std::floor((g.y() - lo.y()) / c);
        if (fx < 0 || fy < 0 || fx >= nxd || fy >= nyd)
            return -1;
        return static_cast<std::int64_t>(fy) * nx + static_cast<std::int64_t>(fx);
    };
    struct Height
    {
        double highest = -std::numeric_limits<double>::infinity(), lowest = std::numeric_limits<double>::infinity(), sum = 0;
        std::size_t count = 0;
        void add(double z)
        {
            highest = std::max(highest, z);
            lowest = std::min(lowest, z);
            sum += z;
            ++count;
        }
        double value(RegionReportParams::ColumnHeight kind) const
        {
            switch (kind) {
            case RegionReportParams::ColumnHeight::Highest: return highest;
            case RegionReportParams::ColumnHeight::Lowest: return lowest;
            default: return sum / static_cast<double>(count);
            }
        }
    };
    struct Column
    {
        Height region, other;
    };
    std::unordered_map<std::int64_t, Column> columns;
    for (std::size_t i : indices) {
        const Eigen::Vector3d g = cloud.globalPosition(i);
        const std::int64_t key = columnOf(g);
        if (key >= 0)
            columns[key].region.add(g.z());
    }
    for (std::size_t i = 0; i < other.size(); ++i) {
        if (!other.positions()[i].allFinite())
            continue;
        const Eigen::Vector3d g = other.globalPosition(i);
        const std::int64_t key = columnOf(g);
        const auto it = key < 0 ? columns.end() : columns.find(key);
        if (it != columns.end())
            it->second.other.add(g.z());
    }
    // Each column weighs its area inside the footprint; coverage is the share
    // of the whole footprint's area whose columns both epochs reach.
    const detail::FootprintCells cells(r.footprint, lo, c);
    double added = 0.0, removed = 0.0, coveredArea = 0.0;
    std::size_t visited = 0;
    for (const auto& [key, column] : columns) {
        if (++visited % 4096 == 0 && ticker)
            ticker->checkCancel();
        if (column.other.count == 0)
            continue;
        const double area = cells.areaIn(key % nx, key / nx);
        if (area == 0.0)
            continue;
        coveredArea += area;
        const double regionHeight = column.region.value(params.columnHeight), otherHeight = column.other.value(params.columnHeight);
        const double rise = params.regionInLaterEpoch ? regionHeight - otherHeight : otherHeight - regionHeight;
        (rise > 0 ? added : removed) += std::abs(rise) * area;
    }
    const double totalArea = cells.totalArea();
    r.volume = added - removed;
    r.volumeAdded = added;
    r.volumeRemoved = removed;
    r.volumeCoverage = totalArea > 0 ? coveredArea / totalArea : 0.0;
}

} // namespace

// 1.5 times the median distance of the region's points to their 4th nearest
// neighbour: one cell per point spacing and a half, so the sampling leaves few holes.
double outlineCellFor(const std::vector<Eigen::Vector3f>& local, const BoundingBox& bounds)
{
    const octree::Octree tree(local.data(), local.size());
    const std::size_t k = std::min<std::size_t>(5, local.size());
    std::vector<octree::Neighbour> neighbours;
    int level = 1;
    for (int l = 1; l <= octree::kMaxLevel; ++l)
        if (tree.levelStatistics(l).meanPointsPerCell >= 8.0)
            level = l;
    tree.nearestBatch(local.data(), local.size(), k, level, neighbours);
    std::vector<float> fourth;
    fourth.reserve(local.size());
    for (std::size_t i = 0; i < local.size(); ++i)
        fourth.push_back(std::sqrt(neighbours[i * k + k - 1].squaredDistance));
    std::nth_element(fourth.begin(), fourth.begin() + fourth.size() / 2, fourth.end());
    const double cell = 1.5 * fourth[fourth.size() / 2];
    if (cell > 0.0)
        return cell;
    return std::max(1e-3, 1e-2 * (bounds.max - bounds.min).norm()); // a single point, or duplicates: some small square
}


std::vector<RegionStatistics> regionReport(const PointCloud& cloud, const RegionReportParams& params, ProgressObserver* progress)
{
    const ScalarField* regionField = cloud.field(params.regionField);
    if (!regionField)
        throw Error(ErrorCode::InvalidArgument, "region report: cloud '" + cloud.name + "' has no field '" + params.regionField + "'");
    const ScalarField* distance = nullptr;
    if (!params.distanceField.empty()) {
        distance = cloud.field(params.distanceField);
        if (!distance)
            throw Error(ErrorCode::InvalidArgument, "region report: cloud '" + cloud.name + "' has no field '" + params.distanceField + "'");
    }
    const ScalarField* uncertainty = nullptr;
    if (!params.uncertaintyField.empty()) {
        uncertainty = cloud.field(params.uncertaintyField);
        if (!uncertainty)
            throw Error(ErrorCode::InvalidArgument, "region report: cloud '" + cloud.name + "' has no field '" + params.uncertaintyField + "'");
        if (!distance)
            throw Error(ErrorCode::InvalidArgument, "region report: an uncertainty field needs the distances it belongs to");
    } else if (params.distanceField == fields::kM3c2Distance) {
        uncertainty = cloud.field(fields::kM3c2Uncertainty);
    }
    if (!(params.outlineCellSize >= 0.0 && std::isfinite(params.outlineCellSize)) ||
        !(params.volumeCellSize >= 0.0 && std::isfinite(params.volumeCellSize)))
        throw Error(ErrorCode::InvalidArgument, "region report: cell sizes must be finite and >= 0 (0: automatic)");

    std::map<int, std::vector<std::size_t>> members;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!regionField->hasValue(i) || !cloud.positions()[i].allFinite())
            continue;
        const double v = regionField->value(i);
        if (!(v >= 1.0 && v <= 2147483647.0 && v == std::floor(v)))
            throw Error(ErrorCode::InvalidData, "region report: field '" + params.regionField + "' holds " + std::to_string(v) +
                                                    " at point " + std::to_string(i) + ", not a positive integer id");
        members[static_cast<int>(v)].push_back(i);
    }

    std::vector<RegionStatistics> report;
    ProgressTicker ticker(progress, "Region report", members.size());
    for (const auto& [id, indices] : members) {
        ticker.step();
        RegionStatistics r;
        r.id = id;
        r.pointCount = indices.size();
        const double count = static_cast<double>(indices.size());
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        std::vector<Eigen::Vector3f> local;
        local.reserve(indices.size());
        for (std::size_t i : indices) {
            local.push_back(cloud.positions()[i]);
            mean += cloud.positions()[i].cast<double>();
        }
        mean /= count;
        Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
        r.bounds.min = r.bounds.max = cloud.globalPosition(indices.front());
        r.bounds.empty = false;
        for (std::size_t i : indices) {
            const Eigen::Vector3d d = cloud.positions()[i].cast<double>() - mean;
            covariance += d * d.transpose();
            const Eigen::Vector3d g = cloud.globalPosition(i);
            r.bounds.min = r.bounds.min.cwiseMin(g);
            r.bounds.max = r.bounds.max.cwiseMax(g);
        }
        r.centroid = cloud.origin() + mean;
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance / count);
        // Eigenvalues increase: the first vector is the plane's normal.
        r.planeNormal = eigen.eigenvectors().col(0).normalized();
        const Eigen::Vector3d u = eigen.eigenvectors().col(2).normalized();
        const Eigen::Vector3d v = r.planeNormal.cross(u);

        const double cell = params.outlineCellSize > 0 ? params.outlineCellSize : outlineCellFor(local, r.bounds);
        r.outlineCellSize = cell;
        std::vector<Eigen::Vector2d> planar;
        planar.reserve(indices.size());
        for (const auto& p : local) {
            const Eigen::Vector3d d = p.cast<double>() - mean;
            planar.emplace_back(d.dot(u), d.dot(v));
        }
        const Outline2d outline = concaveOutline(planar, cell);
        r.outlineArea = outline.area;
        for (const auto& ring : outline.rings) {
            std::vector<Eigen::Vector3d> lifted;
            for (const auto& q : ring)
                lifted.push_back(r.centroid + q.x() * u + q.y() * v);
            r.outlines.push_back(std::move(lifted));
        }
        // The footprint: the same outline of the points seen from above.
        for (std::size_t j = 0; j < local.size(); ++j)
            planar[j] = (local[j].cast<double>() - mean).head<2>();
        const Outline2d plan = concaveOutline(planar, cell);
        r.footprintArea = plan.area;
        for (const auto& ring : plan.rings) {
            Polygon2d global;
            for (const auto& q : ring)
                global.push_back(q + r.centroid.head<2>());
            r.footprint.push_back(std::move(global));
        }

        if (distance) {
            double sum = 0.0, squares = 0.0, extreme = 0.0, lodSum = 0.0;
            std::size_t lodCount = 0;
            for (std::size_t i : indices) {
                if (!distance->hasValue(i))
                    continue;
                const double d = distance->value(i);
                sum += d;
                squares += d * d;
                if (r.distanceCount == 0 || std::abs(d) > std::abs(extreme))
                    extreme = d;
                ++r.distanceCount;
                if (uncertainty && uncertainty->hasValue(i)) {
                    lodSum += uncertainty->value(i);
                    ++lodCount;
                }
            }
            if (r.distanceCount > 0) {
                const double n = static_cast<double>(r.distanceCount);
                r.meanDistance = sum / n;
                r.rmsDistance = std::sqrt(squares / n);
                r.maxDistance = extreme;
            }
            if (lodCount > 0) {
                r.distanceVolume = r.outlineArea * r.meanDistance;
                r.distanceVolumeUncertainty = r.outlineArea * lodSum / static_cast<double>(lodCount);
            }
        }

        if (params.reference)
            measureVolume(cloud, indices, *params.reference, params, params.volumeCellSize > 0 ? params.volumeCellSize : cell, r, &ticker);
        report.push_back(std::move(r));
    }
    return report;
}

std::map<int, std::vector<std::size_t>> pointsByRegion(const ScalarField& regionIds)
{
    std::map<int, std::vector<std::size_t>> members;
    for (std::size_t i = 0; i < regionIds.size(); ++i)
        if (regionIds.hasValue(i))
            members[static_cast<int>(std::lround(regionIds.value(i)))].push_back(i);
    return members;
}

} // namespace scandiff
