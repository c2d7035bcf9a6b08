// SPDX-License-Identifier: GPL-3.0-or-later
// Sequential RANSAC for façade planes, after H. Boulaassal's thesis (001,
// §3.4): written here because neither CGAL nor PCL has the thesis's
// orientation-ordered search with its connectivity raster; the random draws
// and the raster are plain code, the fits Eigen's.
#include "SequentialRansac.h"

#include <scandiff/octree/MortonCode.h>

#include <Eigen/Eigenvalues>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <unordered_map>
#include <unordered_set>

namespace scandiff::plugins::detail {

namespace {

constexpr double kDegree = M_PI / 180.0;
//! Hypotheses scored together (in parallel); the best of a batch is chosen by
//! support, then by its place in the batch, so threads never change the result.
constexpr std::size_t kBatch = 32;
//! Points each hypothesis is scored on: enough to tell a plane of
//! `minPoints` among a few million, and a bounded cost per draw.
constexpr std::size_t kScoringSample = 40000;
constexpr std::size_t kMaxIterations = 20000;
constexpr std::size_t kMinIterations = 64;
//! Refused refits of one class before it is given up.
constexpr int kMaxFailures = 12;

//! The thesis's classes of orientation (§3.4.5.2), in its order, then a last
//! pass that takes what is left so that no plane is lost to the 1° test.
enum class PlaneClass { AcrossFacade, Horizontal, Inclined, AlongFacade, Any, Vertical };

const char* className(PlaneClass c)
{
    switch (c) {
    case PlaneClass::AcrossFacade: return "vertical, across the façade";
    case PlaneClass::Horizontal: return "horizontal";
    case PlaneClass::Inclined: return "inclined";
    case PlaneClass::AlongFacade: return "parallel to the façade";
    case PlaneClass::Any: return "any orientation (what the classes left)";
    case PlaneClass::Vertical: return "vertical";
    }
    return "";
}

struct Frame
{
    Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
};

double angleTo(const Eigen::Vector3d& normal, const Eigen::Vector3d& axis)
{
    return std::acos(std::min(1.0, std::abs(normal.dot(axis))));
}

//! Whether a normal belongs to the class, within `tolerance` (radians) of its axis.
bool inClass(PlaneClass c, const Eigen::Vector3d& n, const Frame& f, double tolerance)
{
    switch (c) {
    case PlaneClass::AcrossFacade: return angleTo(n, f.x) <= tolerance;
    case PlaneClass::Horizontal: return angleTo(n, f.z) <= tolerance;
    case PlaneClass::AlongFacade: return angleTo(n, f.y) <= tolerance;
    case PlaneClass::Vertical: return angleTo(n, f.z) >= M_PI / 2 - tolerance;
    case PlaneClass::Any: return true;
    case PlaneClass::Inclined:
        // Away from the three axes (a,b,c all non-zero, §3.4.5.2). A draw is
        // held to the loose tolerance: a draw a few degrees off the wall is
        // the wall, whose turn comes last.
        return angleTo(n, f.x) > tolerance && angleTo(n, f.y) > tolerance && angleTo(n, f.z) > tolerance;
    }
    return false;
}

struct Plane
{
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
    Eigen::Vector3d e1 = Eigen::Vector3d::UnitX(), e2 = Eigen::Vector3d::UnitY(); //!< in the plane (PCA)
};

//! Least-squares plane by PCA (§3.4.7): centroid, and the eigenvector of the smallest eigenvalue as normal.
Plane fitPlane(const std::vector<Eigen::Vector3d>& points, const std::vector<std::uint32_t>& members)
{
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::uint32_t i : members)
        mean += points[i];
    mean /= static_cast<double>(members.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (std::uint32_t i : members) {
        const Eigen::Vector3d d = points[i] - mean;
        covariance.noalias() += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    Plane plane;
    plane.point = mean;
    plane.normal = solver.eigenvectors().col(0).normalized();
    plane.e1 = solver.eigenvectors().col(2).normalized();
    plane.e2 = plane.normal.cross(plane.e1);
    return plane;
}

using Pixel = std::pair<std::int64_t, std::int64_t>;

//! The pixel of `p` in the plane's raster (PCA axes, side `pixel`), and its hash key.
Pixel pixelOf(const Plane& plane, const Eigen::Vector3d& p, double pixel)
{
    const Eigen::Vector3d d = p - plane.point;
    return {static_cast<std::int64_t>(std::floor(d.dot(plane.e1) / pixel)), static_cast<std::int64_t>(std::floor(d.dot(plane.e2) / pixel))};
}

std::uint64_t pixelKey(std::int64_t u, std::int64_t v)
{
    return (static_cast<std::uint64_t>(u) << 32) ^ static_cast<std::uint32_t>(v);
}

//! The largest 8-connected region of the inliers' pixels in their plane
//! (§3.4.6: a binary image, connected regions, the largest kept).
std::vector<std::uint32_t> largestRegion(const std::vector<Eigen::Vector3d>& points, const std::vector<std::uint32_t>& inliers,
                                         const Plane& plane, double pixel)
{
    struct Cell
    {
        std::vector<std::uint32_t> members;
        int label = -1;
    };
    std::unordered_map<std::uint64_t, Cell> cells;
    cells.reserve(inliers.size() / 4 + 1);
    // The occupied pixels, sorted for a walk that never depends on the hash order.
    std::vector<Pixel> coordinates;
    coordinates.reserve(inliers.size());
    for (std::uint32_t i : inliers) {
        const Pixel at = pixelOf(plane, points[i], pixel);
        cells[pixelKey(at.first, at.second)].members.push_back(i);
        coordinates.push_back(at);
    }
    std::sort(coordinates.begin(), coordinates.end());
    coordinates.erase(std::unique(coordinates.begin(), coordinates.end()), coordinates.end());
    int labels = 0, best = -1;
    std::size_t bestArea = 0, bestPoints = 0;
    std::vector<Pixel> stack;
    for (const auto& start : coordinates) {
        Cell& first = cells[pixelKey(start.first, start.second)];
        if (first.label >= 0)
            continue;
        const int label = labels++;
        first.label = label;
        std::size_t area = 0, count = 0;
        stack.assign(1, start);
        while (!stack.empty()) {
            const auto [u, v] = stack.back();
            stack.pop_back();
            const Cell& here = cells[pixelKey(u, v)];
            ++area;
            count += here.members.size();
            for (std::int64_t du = -1; du <= 1; ++du)
                for (std::int64_t dv = -1; dv <= 1; ++dv) {
                    const auto it = cells.find(pixelKey(u + du, v + dv));
                    if (it == cells.end() || it->second.label >= 0)
                        continue;
                    it->second.label = label;
                    stack.emplace_back(u + du, v + dv);
                }
        }
        // The largest area wins; ties by points, then by the first found (the sorted order).
        if (area > bestArea || (area == bestArea && count > bestPoints)) {
            best = label;
            bestArea = area;
            bestPoints = count;
        }
    }
    std::vector<std::uint32_t> region;
    region.reserve(bestPoints);
    for (const auto& [code, cell] : cells)
        if (cell.label == best)
            region.insert(region.end(), cell.members.begin(), cell.members.end());
    std::sort(region.begin(), region.end());
    return region;
}

class SequentialSearch
{
public:
    SequentialSearch(const std::vector<Eigen::Vector3d>& points, const octree::Octree& tree, const SequentialSettings& settings,
                     const std::function<bool()>& keepGoing)
        : points_(points), tree_(tree), settings_(settings), keepGoing_(keepGoing), random_(settings.seed),
          remaining_(points.size(), 1), skipped_(points.size(), 0), rank_(points.size())
    {
        const std::vector<std::uint32_t>& sorted = tree.sortedIndices();
        for (std::size_t k = 0; k < sorted.size(); ++k)
            rank_[sorted[k]] = static_cast<std::uint32_t>(k);
        // The second and third points of a draw come from the first one's
        // octree cell: local draws find a small plane (a column's side) where
        // three points drawn anywhere would almost never lie on it together.
        const double reach = 4.0 * settings.pixel;
        level_ = 1;
        while (level_ < octree::kMaxLevel && tree.cellSize(level_ + 1) >= reach)
            ++level_;
    }

    bool stopped() const { return stopped_; }

    //! The façade's frame: its normal is the largest vertical plane's, horizontal.
    Frame facadeFrame(std::vector<std::string>& notes)
    {
        Frame frame;
        std::fill(skipped_.begin(), skipped_.end(), 0);
        std::optional<Plane> wall;
        for (int attempt = 0; attempt < kMaxFailures && !wall && !stopped_; ++attempt) {
            const std::optional<std::pair<Plane, std::vector<std::uint32_t>>> found = bestPlane(PlaneClass::Vertical, frame);
            if (!found)
                break;
            if (inClass(PlaneClass::Vertical, found->first.normal, frame, 5 * kDegree))
                wall = found->first;
            else
                markSkipped(found->second);
        }
        std::fill(skipped_.begin(), skipped_.end(), 0);
        if (!wall) {
            notes.push_back("sequential RANSAC: no vertical plane found; the façade is taken as facing the y axis");
            return frame;
        }
        frame.y = Eigen::Vector3d(wall->normal.x(), wall->normal.y(), 0).normalized();
        frame.x = frame.y.cross(frame.z);
        return frame;
    }

    //! Every plane of one class, one after the other.
    void extractClass(PlaneClass planeClass, const Frame& frame, std::vector<RansacShape>& planes, std::vector<std::string>& notes)
    {
        std::fill(skipped_.begin(), skipped_.end(), 0);
        const double tolerance = settings_.toleranceDegrees * kDegree;
        const double loose = looseTolerance();
        const std::size_t before = planes.size();
        int failures = 0;
        while (failures < kMaxFailures && !stopped_) {
            const std::optional<std::pair<Plane, std::vector<std::uint32_t>>> found = bestPlane(planeClass, frame);
            if (!found)
                break;
            const Plane& plane = found->first;
            const std::vector<std::uint32_t>& inliers = found->second;
            if (!inClass(planeClass, plane.normal, frame, planeClass == PlaneClass::Inclined ? 0.5 * loose : tolerance)) {
                // Refitted outside the class: its points, and the tails of
                // their noise beyond ds, wait for another class (the tails
                // would otherwise make thin planes of their own).
                markNear(plane, 3.0 * settings_.distance);
                ++failures;
                continue;
            }
            // Connectivity (§3.4.6): the largest region is the plane; the other
            // regions' points go back for the next planes.
            std::vector<std::uint32_t> region = largestRegion(points_, inliers, plane, settings_.pixel);
            if (region.size() < settings_.minPoints) {
                markSkipped(inliers);
                ++failures;
                continue;
            }
            const Plane refit = fitPlane(points_, region); // §3.4.7, on the final points
            // A region that is a strip of another surface crossing the slab
            // (its own fit turns away from the plane) is not this plane.
            if (angleTo(refit.normal, plane.normal) > loose ||
                !inClass(planeClass, refit.normal, frame, planeClass == PlaneClass::Inclined ? 0.5 * loose : tolerance)) {
                markSkipped(inliers);
                ++failures;
                continue;
            }
            RansacShape shape;
            shape.primitive.kind = PrimitiveKind::Plane;
            shape.primitive.point = refit.point;
            shape.primitive.direction = refit.normal;
            for (std::uint32_t i : region)
                remaining_[i] = 0;
            shape.members = std::move(region);
            planes.push_back(std::move(shape));
            failures = 0;
        }
        if (planes.size() > before)
            notes.push_back("sequential RANSAC: " + std::to_string(planes.size() - before) + " plane(s) " + className(planeClass));
    }

private:
    //! A draw's normal may stray a few degrees from its plane's (noise over
    //! a cell): the class is checked loosely on draws, strictly after the refit.
    double looseTolerance() const { return std::max(5.0, 3.0 * settings_.toleranceDegrees) * kDegree; }

    bool usable(std::uint32_t i) const { return remaining_[i] && !skipped_[i]; }

    void markNear(const Plane& plane, double distance)
    {
        for (std::uint32_t i = 0; i < points_.size(); ++i)
            if (remaining_[i] && std::abs(plane.normal.dot(points_[i] - plane.point)) <= distance)
                skipped_[i] = 1;
    }

    void markSkipped(const std::vector<std::uint32_t>& indices)
    {
        for (std::uint32_t i : indices)
            skipped_[i] = 1;
    }

    std::optional<Eigen::Vector4d> drawHypothesis(const std::vector<std::uint32_t>& active)
    {
        const std::uint32_t first = active[random_() % active.size()];
        const octree::MortonCode code = octree::cellCodeAtLevel(tree_.sortedCodes()[rank_[first]], level_);
        const auto [begin, end] = tree_.cellRange(code, level_);
        if (end - begin < 3)
            return std::nullopt;
        std::uint32_t chosen[2];
        for (int k = 0; k < 2; ++k) {
            bool found = false;
            for (int attempt = 0; attempt < 8 && !found; ++attempt) {
                const std::uint32_t candidate = tree_.sortedIndices()[begin + random_() % (end - begin)];
                found = candidate != first && (k == 0 || candidate != chosen[0]) && usable(candidate);
                chosen[k] = candidate;
            }
            if (!found)
                return std::nullopt;
        }
        const Eigen::Vector3d& p0 = points_[first];
        const Eigen::Vector3d a = points_[chosen[0]] - p0, b = points_[chosen[1]] - p0;
        const Eigen::Vector3d normal = a.cross(b);
        if (!(normal.norm() > 1e-9 * a.norm() * b.norm()) || normal.norm() == 0)
            return std::nullopt; // collinear
        const Eigen::Vector3d n = normal.normalized();
        return Eigen::Vector4d(n.x(), n.y(), n.z(), -n.dot(p0));
    }

    //! The best plane of the class by support (adaptive RANSAC, §3.4.3 and
    //! Annex C.2), refitted twice by PCA on its inliers; nullopt when no
    //! plane of the class holds the minimum support.
    std::optional<std::pair<Plane, std::vector<std::uint32_t>>> bestPlane(PlaneClass planeClass, const Frame& frame)
    {
        std::vector<std::uint32_t> active;
        for (std::uint32_t i = 0; i < points_.size(); ++i)
            if (usable(i))
                active.push_back(i);
        if (active.size() < settings_.minPoints)
            return std::nullopt;
        std::vector<std::uint32_t> sample = active;
        if (sample.size() > kScoringSample) {
            std::shuffle(sample.begin(), sample.end(), random_);
            sample.resize(kScoringSample);
        }
        const double scale = static_cast<double>(active.size()) / static_cast<double>(sample.size());
        const double loose = looseTolerance();
        std::optional<Eigen::Vector4d> best;
        std::size_t bestSupport = 0, iterations = 0, needed = kMaxIterations;
        std::vector<Eigen::Vector4d> batch;
        std::vector<std::size_t> support(kBatch);
        while (iterations < std::max(needed, kMinIterations) && iterations < kMaxIterations) {
            if (!keepGoing_()) {
                stopped_ = true;
                return std::nullopt;
            }
            batch.clear();
            for (std::size_t k = 0; k < kBatch; ++k) {
                const std::optional<Eigen::Vector4d> h = drawHypothesis(active);
                if (h && inClass(planeClass, h->head<3>(), frame, loose))
                    batch.push_back(*h);
            }
            iterations += kBatch;
            tbb::parallel_for(std::size_t(0), batch.size(), [&](std::size_t k) {
                const Eigen::Vector4d& h = batch[k];
                std::size_t count = 0;
                for (std::uint32_t i : sample)
                    count += std::abs(h.head<3>().dot(points_[i]) + h[3]) <= settings_.distance;
                support[k] = count;
            });
            for (std::size_t k = 0; k < batch.size(); ++k)
                if (support[k] > bestSupport) {
                    bestSupport = support[k];
                    best = batch[k];
                }
            if (bestSupport > 0) {
                // N = log(1 - P) / log(1 - w q²): w the best support's share,
                // q² the chance that the two neighbours drawn lie on the plane
                // too (1/4 taken: a cell is often shared with another surface).
                const double w = static_cast<double>(bestSupport) / static_cast<double>(sample.size());
                const double good = std::clamp(w * 0.25, 1e-12, 1.0 - 1e-12);
                needed = static_cast<std::size_t>(std::ceil(std::log(1.0 - settings_.probability) / std::log(1.0 - good)));
            }
        }
        if (!best || static_cast<double>(bestSupport) * scale < static_cast<double>(settings_.minPoints))
            return std::nullopt;
        // Inliers among every usable point, and the plane refitted on them
        // until it settles: the draw's plane is only three close points', a
        // few degrees off on a narrow surface (a pilaster's side), and each
        // refit recovers only part of that where a wall crosses the slab.
        Plane plane;
        plane.normal = best->head<3>();
        plane.point = -(*best)[3] * plane.normal;
        std::vector<std::uint32_t> inliers;
        for (int round = 0; round < 20; ++round) {
            inliers.clear();
            for (std::uint32_t i : active)
                if (std::abs(plane.normal.dot(points_[i] - plane.point)) <= settings_.distance)
                    inliers.push_back(i);
            if (inliers.size() < 3)
                return std::nullopt;
            const Plane refit = fitPlane(points_, inliers);
            const bool settled = angleTo(refit.normal, plane.normal) < 0.001 * kDegree &&
                                 std::abs(refit.normal.dot(refit.point - plane.point)) < 0.01 * settings_.distance;
            plane = refit;
            if (settled)
                break;
        }
        inliers.clear();
        for (std::uint32_t i : active)
            if (std::abs(plane.normal.dot(points_[i] - plane.point)) <= settings_.distance)
                inliers.push_back(i);
        return std::make_pair(plane, std::move(inliers));
    }

    const std::vector<Eigen::Vector3d>& points_;
    const octree::Octree& tree_;
    const SequentialSettings& settings_;
    const std::function<bool()>& keepGoing_;
    std::mt19937_64 random_;
    std::vector<char> remaining_, skipped_;
    std::vector<std::uint32_t> rank_;
    int level_ = 1;
    bool stopped_ = false;
};

//! The thesis's "linear errors" (§3.4.6) undone: a plane found early keeps
//! the points of a later plane that lie on their line of intersection (the
//! wall's points along a pilaster's edge), which tilt a narrow plane. A point
//! goes to the later plane when it is closer to it, within ds, and on that
//! plane's surface (a pixel of its raster, or next to one). Returns how many moved.
std::size_t giveBackIntersectionPoints(const std::vector<Eigen::Vector3d>& points, std::vector<RansacShape>& planes, double distance,
                                       double pixel)
{
    struct Surface
    {
        Plane plane;
        std::unordered_set<std::uint64_t> cells;
    };
    std::vector<Surface> surfaces(planes.size());
    for (std::size_t k = 0; k < planes.size(); ++k) {
        surfaces[k].plane = fitPlane(points, planes[k].members);
        for (std::uint32_t i : planes[k].members) {
            const auto [u, v] = pixelOf(surfaces[k].plane, points[i], pixel);
            surfaces[k].cells.insert(pixelKey(u, v));
        }
    }
    auto onSurface = [&](const Surface& s, const Eigen::Vector3d& p) {
        const auto [u, v] = pixelOf(s.plane, p, pixel);
        for (std::int64_t du = -1; du <= 1; ++du)
            for (std::int64_t dv = -1; dv <= 1; ++dv)
                if (s.cells.count(pixelKey(u + du, v + dv)))
                    return true;
        return false;
    };
    std::vector<std::vector<std::uint32_t>> given(planes.size());
    std::size_t moved = 0;
    for (std::size_t k = 0; k < planes.size(); ++k) {
        std::vector<std::uint32_t> kept;
        kept.reserve(planes[k].members.size());
        for (std::uint32_t i : planes[k].members) {
            const Eigen::Vector3d& p = points[i];
            const double own = std::abs(surfaces[k].plane.normal.dot(p - surfaces[k].plane.point));
            std::size_t target = planes.size();
            double best = std::min(own, distance);
            for (std::size_t j = k + 1; j < planes.size(); ++j) {
                const double d = std::abs(surfaces[j].plane.normal.dot(p - surfaces[j].plane.point));
                if (d < best && onSurface(surfaces[j], p)) {
                    best = d;
                    target = j;
                }
            }
            if (target < planes.size()) {
                given[target].push_back(i);
                ++moved;
            } else {
                kept.push_back(i);
            }
        }
        planes[k].members = std::move(kept);
    }
    for (std::size_t k = 0; k < planes.size(); ++k) {
        planes[k].members.insert(planes[k].members.end(), given[k].begin(), given[k].end());
        std::sort(planes[k].members.begin(), planes[k].members.end());
        if (planes[k].members.size() >= 3) {
            const Plane refit = fitPlane(points, planes[k].members);
            planes[k].primitive.point = refit.point;
            planes[k].primitive.direction = refit.normal;
        }
    }
    return moved;
}

} // namespace

SequentialOutcome sequentialPlanes(const std::vector<Eigen::Vector3d>& points, const octree::Octree& tree,
                                   const SequentialSettings& settings, const std::function<bool()>& keepGoing)
{
    SequentialOutcome outcome;
    if (points.size() < settings.minPoints)
        return outcome;
    SequentialSearch search(points, tree, settings, keepGoing);
    const Frame frame = search.facadeFrame(outcome.notes);
    outcome.facadeNormal = frame.y;
    for (PlaneClass c : {PlaneClass::AcrossFacade, PlaneClass::Horizontal, PlaneClass::Inclined, PlaneClass::AlongFacade, PlaneClass::Any})
        search.extractClass(c, frame, outcome.planes, outcome.notes);
    if (search.stopped())
        return SequentialOutcome{};
    if (const std::size_t moved = giveBackIntersectionPoints(points, outcome.planes, settings.distance, settings.pixel))
        outcome.notes.push_back("sequential RANSAC: " + std::to_string(moved) +
                                " points on lines where planes meet given to the later plane they lie on");
    return outcome;
}

} // namespace scandiff::plugins::detail
