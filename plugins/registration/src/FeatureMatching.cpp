// SPDX-License-Identifier: GPL-3.0-or-later
#include "FeatureMatching.h"

#include <scandiff/core/Error.h>

// Compiled here rather than linked: PCL's precompiled libraries would bring
// libpcl_features and friends, some 30 MB of resident memory at start-up in
// every process (measured), for one kd-tree.
#define PCL_NO_PRECOMPILE
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace scandiff::plugins::detail {

namespace {

pcl::PointCloud<pcl::FPFHSignature33>::Ptr toPcl(const std::vector<Descriptor>& d)
{
    auto cloud = pcl::make_shared<pcl::PointCloud<pcl::FPFHSignature33>>();
    cloud->resize(d.size());
    for (std::size_t i = 0; i < d.size(); ++i)
        std::copy(d[i].begin(), d[i].end(), (*cloud)[i].histogram);
    return cloud;
}

std::vector<std::size_t> nearest(const pcl::KdTreeFLANN<pcl::FPFHSignature33>& tree, const pcl::PointCloud<pcl::FPFHSignature33>& queries)
{
    std::vector<std::size_t> result(queries.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, queries.size()), [&](const tbb::blocked_range<std::size_t>& range) {
        pcl::Indices index(1);
        std::vector<float> distance(1);
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            tree.nearestKSearch(queries[i], 1, index, distance);
            result[i] = static_cast<std::size_t>(index[0]);
        }
    });
    return result;
}

} // namespace

std::vector<std::pair<std::size_t, std::size_t>> matchDescriptors(const std::vector<Descriptor>& a, const std::vector<Descriptor>& b,
                                                                  std::size_t minimumMutual)
{
    if (a.empty() || b.empty())
        return {};
    const auto cloudA = toPcl(a), cloudB = toPcl(b);
    pcl::KdTreeFLANN<pcl::FPFHSignature33> treeA, treeB;
    treeA.setInputCloud(cloudA);
    treeB.setInputCloud(cloudB);
    // (Lowe's ratio test, tried on the synthetic site, did not raise the share
    // of right matches: most wrong ones are ground against ground.)
    const std::vector<std::size_t> aToB = nearest(treeB, *cloudA), bToA = nearest(treeA, *cloudB);
    std::vector<std::pair<std::size_t, std::size_t>> mutual, forward;
    for (std::size_t i = 0; i < a.size(); ++i) {
        forward.emplace_back(i, aToB[i]);
        if (bToA[aToB[i]] == i)
            mutual.emplace_back(i, aToB[i]);
    }
    return mutual.size() >= minimumMutual ? mutual : forward;
}

} // namespace scandiff::plugins::detail
