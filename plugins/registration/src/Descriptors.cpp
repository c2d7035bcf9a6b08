// SPDX-License-Identifier: GPL-3.0-or-later
// Fast Point Feature Histograms (Rusu, Blodow and Beetz, "Fast Point Feature
// Histograms (FPFH) for 3D registration", ICRA 2009), written here on the
// octree's radius batches rather than taken from PCL: PCL's implementation
// lives in libpcl_features, whose loading alone adds some 30 MB of resident
// memory to every process that links it (measured with /usr/bin/time on
// Debian 12's PCL 1.13), more than a whole ICP run; the descriptor itself is
// short. Binning and weighting follow the paper (and PCL's conventions, so
// the descriptors are comparable): 11 bins per angle, each histogram
// normalised to 100, neighbours' histograms weighted by 1 / distance.
#include "FeatureMatching.h"

#include <scandiff/octree/Octree.h>

#include <Eigen/Geometry>

#include <tbb/parallel_for.h>

#include <cmath>

namespace scandiff::plugins::detail {

namespace {

constexpr int kBins = 11;
constexpr double kPi = 3.14159265358979323846;

//! The three angles of the Darboux frame between two oriented points
//! (paper §III): the frame is built on the point whose normal is the more
//! aligned with the segment, so the result does not depend on the order.
//! False when the points coincide or the frame is undefined.
bool pairAngles(const Eigen::Vector3d& p1, const Eigen::Vector3d& n1, const Eigen::Vector3d& p2, const Eigen::Vector3d& n2,
                double& alpha, double& phi, double& theta)
{
    Eigen::Vector3d d = p2 - p1;
    const double length = d.norm();
    if (!(length > 0))
        return false;
    d /= length;
    Eigen::Vector3d u = n1, other = n2;
    double cosine = n1.dot(d);
    if (std::acos(std::min(1.0, std::abs(cosine))) > std::acos(std::min(1.0, std::abs(n2.dot(d))))) {
        u = n2;
        other = n1;
        d = -d;
        cosine = n2.dot(d);
    }
    Eigen::Vector3d v = d.cross(u);
    const double vLength = v.norm();
    if (!(vLength > 0))
        return false;
    v /= vLength;
    const Eigen::Vector3d w = u.cross(v);
    phi = cosine;
    alpha = v.dot(other);
    theta = std::atan2(w.dot(other), u.dot(other));
    return true;
}

int binOf(double value, double low, double high)
{
    const int b = static_cast<int>(std::floor(kBins * (value - low) / (high - low)));
    return std::min(std::max(b, 0), kBins - 1);
}

} // namespace

void fpfhDescriptors(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& normals, double radius,
                     std::vector<Descriptor>& descriptors, std::vector<char>& valid)
{
    const std::size_t n = points.size();
    descriptors.assign(n, Descriptor{});
    valid.assign(n, 0);
    if (n == 0)
        return;
    const octree::Octree tree(points.data(), n);
    // The neighbourhoods, kept for both passes (a thinned cloud: some tens
    // of neighbours a point).
    std::vector<std::vector<octree::Neighbour>> neighbours(n);
    tree.withinRadiusBatch(points.data(), n, static_cast<float>(radius),
                           [&](std::uint32_t query, const octree::Neighbour* found, std::size_t count) {
                               auto& list = neighbours[query];
                               for (std::size_t i = 0; i < count; ++i)
                                   if (found[i].index != query)
                                       list.push_back(found[i]);
                           });
    // Simplified histograms (SPFH): each point against its neighbours.
    std::vector<Descriptor> simplified(n, Descriptor{});
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
        const Eigen::Vector3d p = points[i].cast<double>(), np = normals[i].cast<double>();
        std::size_t counted = 0;
        Descriptor h{};
        for (const auto& q : neighbours[i]) {
            double alpha, phi, theta;
            if (!pairAngles(p, np, points[q.index].cast<double>(), normals[q.index].cast<double>(), alpha, phi, theta))
                continue;
            h[static_cast<std::size_t>(binOf(theta, -kPi, kPi))] += 1;
            h[static_cast<std::size_t>(kBins + binOf(alpha, -1, 1))] += 1;
            h[static_cast<std::size_t>(2 * kBins + binOf(phi, -1, 1))] += 1;
            ++counted;
        }
        if (counted > 0)
            for (float& v : h)
                v *= 100.0f / static_cast<float>(counted);
        simplified[i] = h;
    });
    // FPFH: the point's own SPFH plus its neighbours', weighted by 1 /
    // distance, each of the three histograms brought back to a sum of 100.
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
        double sums[3 * kBins] = {};
        bool any = false;
        for (const auto& q : neighbours[i]) {
            const double distance = std::sqrt(static_cast<double>(q.squaredDistance));
            if (!(distance > 0))
                continue;
            for (int b = 0; b < 3 * kBins; ++b)
                sums[b] += simplified[q.index][static_cast<std::size_t>(b)] / distance;
            any = true;
        }
        if (!any)
            return;
        Descriptor& d = descriptors[i];
        for (int part = 0; part < 3; ++part) {
            double total = 0;
            for (int b = 0; b < kBins; ++b)
                total += sums[part * kBins + b];
            const double scale = total > 0 ? 100.0 / total : 0.0;
            for (int b = 0; b < kBins; ++b) {
                const auto at = static_cast<std::size_t>(part * kBins + b);
                d[at] = static_cast<float>(sums[at] * scale + simplified[i][at]);
            }
        }
        valid[i] = 1;
    });
}

} // namespace scandiff::plugins::detail
