// SPDX-License-Identifier: GPL-3.0-or-later
//! Writes a synthetic terrestrial-scan-like cloud for benchmarks: a gently
//! undulating terrain with a wall, georeferenced (UTM-like coordinates), with
//! colours, intensity, classification and gps_time, like a real LAS/PLY scan.
//! Usage: scandiff-make-scan POINTS OUTPUT [SEED]
//!        scandiff-make-scan --mesh N OUTPUT   (the terrain as an N x N vertex grid:
//!                                              2 (N-1)^2 triangles, 300 -> 178,802)
//!        scandiff-make-scan --terrain POINTS SIZE OUTPUT [SEED] [--scan-order]
//!                                             (terrain only, SIZE x SIZE m: the
//!                                              processing benchmarks' 1 M points
//!                                              over 100 x 100 m; points in random
//!                                              order, or with --scan-order in an
//!                                              airborne sweep's: along scan lines
//!                                              10 cm apart, back and forth, with
//!                                              a gps_time of 500,000 points a second)
//!        scandiff-make-scan --site POINTS OUTPUT SEED [--changed]
//!                           [--motion YAW,PITCH,ROLL,TX,TY,TZ] [--x-range LOW,HIGH]
//!                                             (the registration tests' site of
//!                                              tests/support/SyntheticSite.h at
//!                                              UTM coordinates, 2 mm of noise;
//!                                              --changed: the second epoch;
//!                                              --motion: the scan moved by it
//!                                              (degrees about Z, Y, X, then metres,
//!                                              turning about the site's centre);
//!                                              --x-range: only points in it, a
//!                                              station's view. Writes the matrix
//!                                              that registers it back, moving ->
//!                                              site, to OUTPUT.truth.txt)
//!        scandiff-make-scan --primitives POINTS OUTPUT SEED
//!                                             (the primitive tests' scene of
//!                                              tests/support/PrimitiveScene.h:
//!                                              15 known shapes, 5 mm of noise,
//!                                              5 % clutter, no normals; the truth
//!                                              to OUTPUT.truth.txt, a shape a line)
//!        scandiff-make-scan --facade POINTS OUTPUT SEED
//!                                             (the sequential-RANSAC test's façade:
//!                                              11 planes, turned 35° at UTM
//!                                              coordinates, 3 mm of noise, 2 %
//!                                              clutter; truth as above)

#include "PrimitiveScene.h"
#include "SyntheticSite.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/io/FileIO.h>
#include <scandiff/io/ResultFiles.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace {

float terrainHeight(float x, float y)
{
    return 2.0f * std::sin(x * 0.05f) * std::cos(y * 0.03f);
}

int writeTerrainMesh(int n, const char* output)
{
    scandiff::Mesh mesh;
    mesh.vertices.setOrigin({512000.0, 5423000.0, 100.0});
    mesh.vertices.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
    const float step = 200.0f / static_cast<float>(n - 1);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const float x = static_cast<float>(i) * step, y = static_cast<float>(j) * step;
            mesh.vertices.positions()[static_cast<std::size_t>(j * n + i)] = {x, y, terrainHeight(x, y)};
        }
    for (int j = 0; j + 1 < n; ++j)
        for (int i = 0; i + 1 < n; ++i) {
            const auto a = static_cast<std::uint32_t>(j * n + i), b = a + 1, c = a + static_cast<std::uint32_t>(n), d = c + 1;
            mesh.triangles.push_back({a, b, d});
            mesh.triangles.push_back({a, d, c});
        }
    scandiff::io::FormatRegistry registry;
    scandiff::io::registerBuiltinFormats(registry);
    scandiff::io::writeMesh(registry, mesh, output);
    std::cout << "wrote " << output << " (" << mesh.triangles.size() << " triangles)\n";
    return 0;
}

//! Puts the points in the order an airborne scanner takes them: along scan
//! lines 10 cm apart, back and forth, timed at 500,000 points a second. Real
//! LAZ files keep that order (or a spatial one), which their compression
//! relies on; the random order of the other benchmarks is LAZ's worst case.
void putInScanOrder(scandiff::PointCloud& cloud)
{
    const std::size_t n = cloud.size();
    auto lineOf = [&](std::size_t i) { return static_cast<long>(std::floor(cloud.positions()[i].y() / 0.1f)); };
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        const long la = lineOf(a), lb = lineOf(b);
        if (la != lb)
            return la < lb;
        const float xa = cloud.positions()[a].x(), xb = cloud.positions()[b].x();
        return la % 2 == 0 ? xa < xb : xa > xb;
    });
    scandiff::PointCloud sorted = cloud.subset(order);
    auto& time = sorted.addField("gps_time");
    time.setOffset(400000.0);
    for (std::size_t i = 0; i < n; ++i)
        time.values()[i] = static_cast<float>(static_cast<double>(i) * 2e-6);
    cloud = std::move(sorted);
}

//! A terrain scan without the wall: uniform over size x size metres, 3 mm of
//! noise, colours and intensity.
int writeTerrainScan(std::size_t n, float size, const char* output, unsigned seed, bool scanOrder)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, size);
    std::normal_distribution<float> noise(0.0f, 0.003f);
    scandiff::PointCloud cloud;
    cloud.name = "terrain";
    cloud.setOrigin({512000.0, 5423000.0, 100.0});
    cloud.resize(n);
    auto& colours = cloud.enableColors();
    auto& intensity = cloud.addField("intensity");
    for (std::size_t i = 0; i < n; ++i) {
        const float x = u(rng), y = u(rng), z = terrainHeight(x, y) + noise(rng);
        cloud.positions()[i] = {x, y, z};
        colours[i] = {static_cast<std::uint8_t>(2.5f * x), static_cast<std::uint8_t>(2.5f * y), static_cast<std::uint8_t>(128 + 50 * z)};
        intensity.values()[i] = static_cast<float>(i % 4096);
    }
    if (scanOrder)
        putInScanOrder(cloud);
    scandiff::io::FormatRegistry registry;
    scandiff::io::registerBuiltinFormats(registry);
    scandiff::io::writePointCloud(registry, cloud, output);
    std::cout << "wrote " << output << " (" << n << " points)\n";
    return 0;
}

int writeSite(int argc, char** argv)
{
    using namespace scandiff;
    const Eigen::Vector3d utm(512000.0, 5423000.0, 100.0);
    test::SiteOptions options;
    options.points = std::stoull(argv[2]);
    options.seed = static_cast<unsigned>(std::stoul(argv[4]));
    options.origin = utm;
    Eigen::Matrix4d motion = Eigen::Matrix4d::Identity();
    double low = -1e9, high = 1e9;
    for (int a = 5; a < argc; ++a) {
        const std::string option = argv[a];
        if (option == "--changed") {
            options.changed = true;
        } else if (option == "--motion" && a + 1 < argc) {
            const std::vector<double> v = parseNumberList(argv[++a], "--motion");
            if (v.size() != 6)
                throw Error(ErrorCode::InvalidArgument, "--motion is YAW,PITCH,ROLL,TX,TY,TZ");
            motion = test::rigidMotionAbout(v[0], v[1], v[2], Eigen::Vector3d(v[3], v[4], v[5]), utm);
        } else if (option == "--x-range" && a + 1 < argc) {
            const std::vector<double> v = parseNumberList(argv[++a], "--x-range");
            if (v.size() != 2)
                throw Error(ErrorCode::InvalidArgument, "--x-range is LOW,HIGH");
            low = v[0];
            high = v[1];
        } else {
            throw Error(ErrorCode::InvalidArgument, "unknown option " + option);
        }
    }
    PointCloud site = test::syntheticSite(options);
    std::vector<std::size_t> seen;
    for (std::size_t i = 0; i < site.size(); ++i) {
        const double x = site.positions()[i].x();
        if (x >= low && x <= high)
            seen.push_back(i);
    }
    PointCloud scan = transformCloud(site.subset(seen), motion, "synthetic motion");
    scan.transformHistory().clear();
    scan.name = std::filesystem::path(argv[3]).stem().string();
    io::FormatRegistry registry;
    io::registerBuiltinFormats(registry);
    io::writePointCloud(registry, scan, argv[3]);
    io::writeMatrix(motion.inverse(), std::string(argv[3]) + ".truth.txt");
    std::cout << "wrote " << argv[3] << " (" << scan.size() << " points) and " << argv[3] << ".truth.txt\n";
    return 0;
}

int writePrimitiveScene(std::size_t points, const std::string& output, unsigned seed, bool facade)
{
    using namespace scandiff;
    test::PrimitiveScene scene =
        facade ? test::makePrimitiveScene(test::facadeSceneShapes(35.0 * M_PI / 180.0, Eigen::Vector3d::Zero()), points, 0.003, 0.02, seed, false)
               : test::makePrimitiveScene(test::testSceneShapes(), points, 0.005, 0.05, seed, false);
    if (facade) {
        const Eigen::Vector3d at(512300.0, 5401200.0, 150.0);
        scene.cloud.setOrigin(at);
        for (auto& shape : scene.shapes)
            shape.truth.point += at;
    }
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    io::writePointCloud(formats, scene.cloud, output);
    std::string truth;
    for (const auto& shape : scene.shapes)
        truth += shape.label + " " + primitiveText(shape.truth) + "\n";
    std::ofstream(output + ".truth.txt") << truth;
    return 0;
}

} // namespace

int main(int argc, char** argv)
{
    if (argc == 5 && (std::string(argv[1]) == "--primitives" || std::string(argv[1]) == "--facade")) {
        try {
            return writePrimitiveScene(std::stoull(argv[2]), argv[3], static_cast<unsigned>(std::stoul(argv[4])),
                                       std::string(argv[1]) == "--facade");
        } catch (const std::exception& e) {
            std::cerr << "error: " << e.what() << '\n';
            return 1;
        }
    }
    if (argc >= 5 && std::string(argv[1]) == "--site") {
        try {
            return writeSite(argc, argv);
        } catch (const std::exception& e) {
            std::cerr << "error: " << e.what() << '\n';
            return 1;
        }
    }
    if (argc >= 5 && argc <= 7 && std::string(argv[1]) == "--terrain") {
        try {
            const bool scanOrder = std::string(argv[argc - 1]) == "--scan-order";
            const int positional = argc - (scanOrder ? 1 : 0);
            const unsigned seed = positional == 6 ? static_cast<unsigned>(std::stoul(argv[5])) : 1u;
            return writeTerrainScan(std::stoull(argv[2]), std::stof(argv[3]), argv[4], seed, scanOrder);
        } catch (const std::exception& e) {
            std::cerr << "error: " << e.what() << '\n';
            return 1;
        }
    }
    if (argc == 4 && std::string(argv[1]) == "--mesh") {
        try {
            return writeTerrainMesh(std::stoi(argv[2]), argv[3]);
        } catch (const std::exception& e) {
            std::cerr << "error: " << e.what() << '\n';
            return 1;
        }
    }
    if (argc < 3) {
        std::cerr << "usage: scandiff-make-scan POINTS OUTPUT [SEED]\n";
        return 2;
    }
    try {
        const auto n = static_cast<std::size_t>(std::stoull(argv[1]));
        const unsigned seed = argc > 3 ? static_cast<unsigned>(std::stoul(argv[3])) : 1u;
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> u(0.0f, 200.0f);
        std::normal_distribution<float> noise(0.0f, 0.003f);
        scandiff::PointCloud cloud;
        cloud.setOrigin({512000.0, 5423000.0, 100.0});
        cloud.resize(n);
        auto& colours = cloud.enableColors();
        for (const char* name : {"intensity", "classification", "gps_time"})
            cloud.addField(name);
        // References once all exist: adding a field may move the others.
        auto& intensity = *cloud.field("intensity");
        auto& classification = *cloud.field("classification");
        auto& gps = *cloud.field("gps_time");
        gps.setOffset(3.0e8);
        for (std::size_t i = 0; i < n; ++i) {
            const float x = u(rng), y = u(rng);
            const bool wall = i % 5 == 0;
            const float z = wall ? u(rng) * 0.05f : terrainHeight(x, y);
            cloud.positions()[i] = {wall ? 100.0f + noise(rng) : x, y, z + noise(rng)};
            colours[i] = {static_cast<std::uint8_t>(x), static_cast<std::uint8_t>(y), static_cast<std::uint8_t>(128 + 50 * z)};
            intensity.values()[i] = static_cast<float>(i % 4096);
            classification.values()[i] = wall ? 6.0f : 2.0f;
            gps.setValue(i, 3.0e8 + static_cast<double>(i) * 1e-5);
        }
        scandiff::io::FormatRegistry registry;
        scandiff::io::registerBuiltinFormats(registry);
        scandiff::io::writePointCloud(registry, cloud, argv[2]);
        std::cout << "wrote " << argv[2] << " (" << n << " points)\n";
    } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << '\n';
        return 1;
    }
    return 0;
}
