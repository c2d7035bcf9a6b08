// SPDX-License-Identifier: GPL-3.0-or-later
#include "FeatureMatching.h"

#include <scandiff/core/Error.h>

// FLANN itself (header-only), not PCL's wrapper of it: PCL's precompiled
// libraries would bring libpcl_features and friends, some 30 MB of resident
// memory at start-up in every process (measured), for one kd-tree. One
// single-tree index searched without a limit on checks: exact nearest
// neighbours, as PCL's KdTreeFLANN gives.
#include <flann/flann.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace scandiff::plugins::detail {

namespace {

using DescriptorIndex = flann::Index<flann::L2_Simple<float>>;

//! The descriptors as one row-major matrix; FLANN reads it in place.
flann::Matrix<float> asMatrix(const std::vector<Descriptor>& d)
{
    return flann::Matrix<float>(const_cast<float*>(d.front().data()), d.size(), d.front().size());
}

std::vector<std::size_t> nearest(const DescriptorIndex& tree, const std::vector<Descriptor>& queries)
{
    std::vector<std::size_t> result(queries.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, queries.size()), [&](const tbb::blocked_range<std::size_t>& range) {
        std::size_t index = 0;
        float distance = 0;
        flann::Matrix<std::size_t> indices(&index, 1, 1);
        flann::Matrix<float> distances(&distance, 1, 1);
        flann::SearchParams params(flann::FLANN_CHECKS_UNLIMITED, 0.0f);
        params.cores = 1;
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            flann::Matrix<float> query(const_cast<float*>(queries[i].data()), 1, queries[i].size());
            tree.knnSearch(query, indices, distances, 1, params);
            result[i] = index;
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
    DescriptorIndex treeA(asMatrix(a), flann::KDTreeSingleIndexParams(15)), treeB(asMatrix(b), flann::KDTreeSingleIndexParams(15));
    treeA.buildIndex();
    treeB.buildIndex();
    // (Lowe's ratio test, tried on the synthetic site, did not raise the share
    // of right matches: most wrong ones are ground against ground.)
    const std::vector<std::size_t> aToB = nearest(treeB, a), bToA = nearest(treeA, b);
    std::vector<std::pair<std::size_t, std::size_t>> mutual, forward;
    for (std::size_t i = 0; i < a.size(); ++i) {
        forward.emplace_back(i, aToB[i]);
        if (bToA[aToB[i]] == i)
            mutual.emplace_back(i, aToB[i]);
    }
    return mutual.size() >= minimumMutual ? mutual : forward;
}

} // namespace scandiff::plugins::detail
