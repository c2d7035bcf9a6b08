// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/processing/CrossSections.h>
#include <scandiff/core/segmentation/RegionReport.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace scandiff {

std::vector<CrossSection> crossSections(const PointCloud& cloud, const CrossSectionParams& params, ProgressObserver* progress)
{
    if (params.axis < 0 || params.axis > 2)
        throw Error(ErrorCode::InvalidArgument, "sections: the axis must be x, y or z");
    if (!(params.thickness > 0 && std::isfinite(params.thickness)) || !(params.step > 0 && std::isfinite(params.step)))
        throw Error(ErrorCode::InvalidArgument, "sections: the thickness and the step must be finite and > 0");
    if (!(params.outlineCell >= 0 && std::isfinite(params.outlineCell)))
        throw Error(ErrorCode::InvalidArgument, "sections: the outline cell must be finite and >= 0 (0: automatic)");
    std::vector<CrossSection> sections;
    const BoundingBox box = cloud.bounds();
    if (box.empty)
        return sections;
    const int a = params.axis, u = (a + 1) % 3, v = (a + 2) % 3;
    const double half = params.thickness / 2;
    const double first = params.first.value_or(box.min[a] + half);
    const double last = params.last.value_or(box.max[a] - half);
    if (!std::isfinite(first) || !std::isfinite(last))
        throw Error(ErrorCode::InvalidArgument, "sections: the first and last positions must be finite");
    const double count = last >= first ? std::floor((last - first) / params.step + 1e-9) + 1 : 1;
    if (count > 100000)
        throw Error(ErrorCode::InvalidArgument, "sections: " + std::to_string(count) + " slabs is too many; take a larger step");
    const auto slabs = static_cast<std::size_t>(count);

    // Each point falls in the slabs whose middle is within half a thickness
    // (several when the thickness exceeds the step): found from its position,
    // in one pass, in the cloud's local frame.
    const double origin = cloud.origin()[a];
    std::vector<std::vector<std::size_t>> members(slabs);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3f& p = cloud.positions()[i];
        if (!p.allFinite())
            continue;
        const double x = origin + p[a];
        const double lowest = std::ceil((x - half - first) / params.step - 1e-12);
        const double highest = std::floor((x + half - first) / params.step + 1e-12);
        for (double k = std::max(0.0, lowest); k <= highest && k < count; ++k) {
            const double middle = first + k * params.step;
            if (std::abs(x - middle) <= half)
                members[static_cast<std::size_t>(k)].push_back(i);
        }
    }

    ProgressTicker ticker(progress, "Cross-sections", slabs);
    for (std::size_t k = 0; k < slabs; ++k) {
        ticker.step();
        if (members[k].empty())
            continue;
        CrossSection section;
        section.position = first + static_cast<double>(k) * params.step;
        section.indices = std::move(members[k]);
        // The outline of the points seen along the axis, relative to their mean.
        std::vector<Eigen::Vector3f> local;
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        BoundingBox slabBox;
        slabBox.empty = false;
        slabBox.min = slabBox.max = cloud.globalPosition(section.indices.front());
        for (std::size_t i : section.indices) {
            local.push_back(cloud.positions()[i]);
            mean += cloud.positions()[i].cast<double>();
            slabBox.min = slabBox.min.cwiseMin(cloud.globalPosition(i));
            slabBox.max = slabBox.max.cwiseMax(cloud.globalPosition(i));
        }
        mean /= static_cast<double>(local.size());
        const double cell = params.outlineCell > 0 ? params.outlineCell : outlineCellFor(local, slabBox);
        std::vector<Eigen::Vector2d> planar;
        planar.reserve(local.size());
        for (const Eigen::Vector3f& p : local)
            planar.emplace_back(p[u] - mean[u], p[v] - mean[v]);
        const Outline2d outline = concaveOutline(planar, cell);
        section.area = outline.area;
        const Eigen::Vector3d centre = cloud.origin() + mean;
        for (const Polygon2d& ring : outline.rings) {
            std::vector<Eigen::Vector3d> lifted;
            for (const Eigen::Vector2d& q : ring) {
                Eigen::Vector3d g;
                g[a] = section.position; // in the slab's middle plane
                g[u] = centre[u] + q.x();
                g[v] = centre[v] + q.y();
                lifted.push_back(g);
            }
            section.outlines.push_back(std::move(lifted));
        }
        sections.push_back(std::move(section));
    }
    return sections;
}

} // namespace scandiff
