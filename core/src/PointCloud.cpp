// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/PointCloud.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>

namespace scandiff {

PointCloud PointCloud::clone() const
{
    PointCloud copy;
    copy.name = name;
    copy.origin_ = origin_;
    copy.positions_ = positions_;
    copy.residuals_ = residuals_;
    copy.colors_ = colors_;
    copy.normals_ = normals_;
    copy.fields_ = fields_;
    copy.sensors_ = sensors_;
    copy.history_ = history_;
    copy.grid_ = grid_;
    copy.crs_ = crs_;
    return copy;
}

void PointCloud::shiftOrigin(const Eigen::Vector3d& newOrigin)
{
    const Eigen::Vector3d delta = origin_ - newOrigin;
    for (std::size_t i = 0; i < positions_.size(); ++i) {
        const Eigen::Vector3d exact = (i < residuals_.size() ? exactLocalPosition(i) : positions_[i].cast<double>()) + delta;
        positions_[i] = exact.cast<float>();
        if (i < residuals_.size())
            residuals_[i] = (exact - positions_[i].cast<double>()).cast<float>();
    }
    origin_ = newOrigin;
}

void PointCloud::resize(std::size_t n)
{
    positions_.resize(n, Eigen::Vector3f::Zero());
    if (!residuals_.empty())
        residuals_.resize(n, Eigen::Vector3f::Zero());
    if (!colors_.empty())
        colors_.resize(n);
    if (!normals_.empty())
        normals_.resize(n, Eigen::Vector3f::Zero());
    for (auto& f : fields_)
        f.resize(n);
}

void PointCloud::reserve(std::size_t n)
{
    positions_.reserve(n);
}

std::vector<Rgb8>& PointCloud::enableColors()
{
    if (colors_.size() != positions_.size())
        colors_.assign(positions_.size(), Rgb8{});
    return colors_;
}

std::vector<Eigen::Vector3f>& PointCloud::enableNormals()
{
    if (normals_.size() != positions_.size())
        normals_.assign(positions_.size(), Eigen::Vector3f::Zero());
    return normals_;
}

const ScalarField* PointCloud::field(const std::string& fieldName) const
{
    for (const auto& f : fields_)
        if (f.name() == fieldName)
            return &f;
    return nullptr;
}

ScalarField* PointCloud::field(const std::string& fieldName)
{
    for (auto& f : fields_)
        if (f.name() == fieldName)
            return &f;
    return nullptr;
}

ScalarField& PointCloud::addField(const std::string& fieldName)
{
    if (ScalarField* existing = field(fieldName))
        return *existing;
    fields_.emplace_back(fieldName, positions_.size());
    return fields_.back();
}

ScalarField& PointCloud::addField(ScalarField newField)
{
    if (newField.size() != positions_.size())
        throw Error(ErrorCode::InvalidArgument, "scalar field '" + newField.name() + "' has " +
                                                    std::to_string(newField.size()) + " values for " +
                                                    std::to_string(positions_.size()) + " points");
    if (ScalarField* existing = field(newField.name())) {
        *existing = std::move(newField);
        return *existing;
    }
    fields_.push_back(std::move(newField));
    return fields_.back();
}

ScalarField& PointCloud::addField(ScalarField newField, std::size_t position)
{
    if (field(newField.name()))
        return addField(std::move(newField));
    const std::size_t at = std::min(position, fields_.size());
    addField(std::move(newField)); // checks the size
    std::rotate(fields_.begin() + static_cast<std::ptrdiff_t>(at), fields_.end() - 1, fields_.end());
    return fields_[at];
}

bool PointCloud::removeField(const std::string& fieldName)
{
    auto it = std::find_if(fields_.begin(), fields_.end(), [&](const ScalarField& f) { return f.name() == fieldName; });
    if (it == fields_.end())
        return false;
    fields_.erase(it);
    return true;
}

BoundingBox PointCloud::bounds() const
{
    // Over the cores (the workbench asks after every change of a 20 M-point
    // cloud): minima and maxima are exact whatever the split.
    struct Extent
    {
        Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
        Eigen::Vector3f hi = Eigen::Vector3f::Constant(-std::numeric_limits<float>::infinity());
        bool any = false;
    };
    const Extent extent = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, positions_.size(), 1 << 16), Extent{},
        [&](const tbb::blocked_range<std::size_t>& r, Extent e) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const Eigen::Vector3f& p = positions_[i];
                if (!p.allFinite())
                    continue;
                e.lo = e.lo.cwiseMin(p);
                e.hi = e.hi.cwiseMax(p);
                e.any = true;
            }
            return e;
        },
        [](Extent a, const Extent& b) {
            a.lo = a.lo.cwiseMin(b.lo);
            a.hi = a.hi.cwiseMax(b.hi);
            a.any = a.any || b.any;
            return a;
        });
    BoundingBox box;
    box.empty = !extent.any;
    if (!box.empty) {
        box.min = origin_ + extent.lo.cast<double>();
        box.max = origin_ + extent.hi.cast<double>();
    }
    return box;
}

PointCloud PointCloud::subset(const std::vector<std::size_t>& indices) const
{
    PointCloud out;
    out.name = name;
    out.origin_ = origin_;
    out.sensors_ = sensors_;
    out.history_ = history_;
    out.grid_ = grid_;
    out.crs_ = crs_;
    out.positions_.reserve(indices.size());
    for (std::size_t i : indices) {
        if (i >= positions_.size())
            throw Error(ErrorCode::InvalidArgument, "subset index " + std::to_string(i) + " beyond the " +
                                                        std::to_string(positions_.size()) + " points of '" + name + "'");
        out.positions_.push_back(positions_[i]);
    }
    if (!residuals_.empty()) {
        out.residuals_.reserve(indices.size());
        for (std::size_t i : indices)
            out.residuals_.push_back(residuals_[i]);
    }
    if (hasColors()) {
        out.colors_.reserve(indices.size());
        for (std::size_t i : indices)
            out.colors_.push_back(colors_[i]);
    }
    if (hasNormals()) {
        out.normals_.reserve(indices.size());
        for (std::size_t i : indices)
            out.normals_.push_back(normals_[i]);
    }
    for (const auto& f : fields_)
        out.fields_.push_back(f.subset(indices));
    return out;
}

std::size_t PointCloud::heldBytes() const
{
    std::size_t bytes = (positions_.capacity() + residuals_.capacity() + normals_.capacity()) * sizeof(Eigen::Vector3f) +
                        colors_.capacity() * sizeof(Rgb8);
    for (const ScalarField& field : fields_)
        bytes += field.heldBytes();
    return bytes;
}

std::size_t PointCloud::removeNonFinitePoints()
{
    const std::size_t n = positions_.size();
    std::size_t kept = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (!positions_[i].allFinite())
            continue;
        if (kept != i) {
            positions_[kept] = positions_[i];
            if (!residuals_.empty())
                residuals_[kept] = residuals_[i];
            if (!colors_.empty())
                colors_[kept] = colors_[i];
            if (!normals_.empty())
                normals_[kept] = normals_[i];
            for (auto& f : fields_)
                f.moveValue(i, kept);
        }
        ++kept;
    }
    if (kept != n) {
        positions_.resize(kept);
        if (!residuals_.empty())
            residuals_.resize(kept);
        if (!colors_.empty())
            colors_.resize(kept);
        if (!normals_.empty())
            normals_.resize(kept);
        for (auto& f : fields_)
            f.resize(kept);
    }
    return n - kept;
}

void PointCloud::checkConsistency() const
{
    const std::size_t n = positions_.size();
    auto complain = [&](const std::string& what, std::size_t count) {
        throw Error(ErrorCode::InvalidData, "cloud '" + name + "': " + what + " has " + std::to_string(count) +
                                                " entries for " + std::to_string(n) + " points");
    };
    if (!colors_.empty() && colors_.size() != n)
        complain("colours", colors_.size());
    if (!normals_.empty() && normals_.size() != n)
        complain("normals", normals_.size());
    if (!residuals_.empty() && residuals_.size() != n)
        complain("position residuals", residuals_.size());
    for (const auto& f : fields_)
        if (f.size() != n)
            complain("scalar field '" + f.name() + "'", f.size());
}

Eigen::Vector3d suggestOrigin(const BoundingBox& bounds)
{
    if (bounds.empty)
        return Eigen::Vector3d::Zero();
    const double largest = std::max(bounds.min.cwiseAbs().maxCoeff(), bounds.max.cwiseAbs().maxCoeff());
    // float32 has a 24-bit mantissa: below 1e4 m its step is under 1 mm.
    if (largest < 1e4)
        return Eigen::Vector3d::Zero();
    Eigen::Vector3d origin;
    for (int a = 0; a < 3; ++a)
        origin[a] = std::floor(bounds.min[a] / 1000.0) * 1000.0;
    return origin;
}

} // namespace scandiff
