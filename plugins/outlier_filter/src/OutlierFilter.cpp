// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/plugins/outlier_filter/OutlierFilter.h>

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <string>

namespace scandiff::plugins {

OutlierFilterResult statisticalOutliers(const PointCloud& cloud, const OutlierFilterParams& params,
                                        ProgressObserver* progress)
{
    if (params.neighbours < 1 || params.neighbours > 1000)
        throw Error(ErrorCode::InvalidArgument, "outlier filter: k must be in [1, 1000], got " + std::to_string(params.neighbours));
    if (!(params.nSigma >= 0.0 && params.nSigma <= 100.0))
        throw Error(ErrorCode::InvalidArgument, "outlier filter: n_sigma must be in [0, 100]");
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    const std::size_t n = cloud.size();
    const auto k = static_cast<std::size_t>(params.neighbours);
    // Cells holding about k+1 points keep the ring search short.
    const int level = tree.levelForMeanPopulation(std::max(4.0, static_cast<double>(k + 1)));

    OutlierFilterResult result;
    result.meanDistances.assign(n, 0.0f);
    ProgressTicker ticker(progress, "Statistical outlier filter", n);
    const auto& positions = cloud.positions();
    tbb::enumerable_thread_specific<std::vector<octree::Neighbour>> scratch;
    // Visiting points in Morton order keeps each thread's neighbourhoods in cache.
    const auto& order = tree.sortedIndices();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        auto& neighbours = scratch.local();
        for (std::size_t s = range.begin(); s != range.end(); ++s) {
            const std::uint32_t i = order[s];
            tree.nearest(positions[i], k + 1, level, neighbours);
            double sum = 0.0;
            std::size_t used = 0;
            for (const auto& nb : neighbours) {
                if (nb.index == i || used == k)
                    continue;
                sum += std::sqrt(static_cast<double>(nb.squaredDistance));
                ++used;
            }
            result.meanDistances[i] = used ? static_cast<float>(sum / static_cast<double>(used)) : 0.0f;
        }
        ticker.step(range.size());
    });

    double sum = 0.0, sumSquares = 0.0;
    for (float d : result.meanDistances) {
        sum += d;
        sumSquares += static_cast<double>(d) * d;
    }
    result.mean = sum / static_cast<double>(n);
    const double variance = n > 1 ? (sumSquares - sum * result.mean) / static_cast<double>(n - 1) : 0.0;
    result.standardDeviation = std::sqrt(std::max(0.0, variance));
    result.threshold = result.mean + params.nSigma * result.standardDeviation;
    for (std::size_t i = 0; i < n; ++i)
        if (result.meanDistances[i] <= result.threshold)
            result.inliers.push_back(i);
    return result;
}

} // namespace scandiff::plugins
