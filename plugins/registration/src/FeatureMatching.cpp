// SPDX-License-Identifier: GPL-3.0-or-later
#include "FeatureMatching.h"

#include <scandiff/core/Error.h>

#include <pcl/features/fpfh_omp.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/search/kdtree.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace scandiff::plugins::detail {

void fpfhDescriptors(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& normals, double radius,
                     int threads, std::vector<Descriptor>& descriptors, std::vector<char>& valid)
{
    auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    auto cloudNormals = pcl::make_shared<pcl::PointCloud<pcl::Normal>>();
    cloud->resize(points.size());
    cloudNormals->resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        (*cloud)[i] = pcl::PointXYZ(points[i].x(), points[i].y(), points[i].z());
        (*cloudNormals)[i] = pcl::Normal(normals[i].x(), normals[i].y(), normals[i].z());
    }
    pcl::FPFHEstimationOMP<pcl::PointXYZ, pcl::Normal, pcl::FPFHSignature33> estimation(static_cast<unsigned>(std::max(threads, 1)));
    estimation.setInputCloud(cloud);
    estimation.setInputNormals(cloudNormals);
    estimation.setSearchMethod(pcl::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
    estimation.setRadiusSearch(radius);
    pcl::PointCloud<pcl::FPFHSignature33> features;
    estimation.compute(features);
    if (features.size() != points.size())
        throw Error(ErrorCode::Internal, "global alignment: PCL gave " + std::to_string(features.size()) + " descriptors for " +
                                             std::to_string(points.size()) + " points");
    descriptors.resize(points.size());
    valid.assign(points.size(), 1);
    for (std::size_t i = 0; i < points.size(); ++i) {
        float sum = 0;
        for (int k = 0; k < 33; ++k) {
            descriptors[i][static_cast<std::size_t>(k)] = features[i].histogram[k];
            sum += features[i].histogram[k];
        }
        // PCL fills a point without neighbours with NaN; all zeros carry nothing either.
        valid[i] = std::isfinite(sum) && sum > 0;
    }
}

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
