// SPDX-License-Identifier: GPL-3.0-or-later
//! Writes a synthetic terrestrial-scan-like cloud for benchmarks: a gently
//! undulating terrain with a wall, georeferenced (UTM-like coordinates), with
//! colours, intensity, classification and gps_time, like a real LAS/PLY scan.
//! Usage: scandiff-make-scan POINTS OUTPUT [SEED]

#include <scandiff/core/Error.h>
#include <scandiff/io/FileIO.h>

#include <cmath>
#include <iostream>
#include <random>
#include <string>

int main(int argc, char** argv)
{
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
        auto& intensity = cloud.addField("intensity");
        auto& classification = cloud.addField("classification");
        auto& gps = cloud.addField("gps_time");
        gps.setOffset(3.0e8);
        for (std::size_t i = 0; i < n; ++i) {
            const float x = u(rng), y = u(rng);
            const bool wall = i % 5 == 0;
            const float z = wall ? u(rng) * 0.05f : 2.0f * std::sin(x * 0.05f) * std::cos(y * 0.03f);
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
