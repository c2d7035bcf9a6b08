// SPDX-License-Identifier: GPL-3.0-or-later
//! Makes the demo pair of data/demo from one real scan: the "2019" epoch is the
//! scan itself; the "2024" epoch is an independent-looking resampling of it
//! (90 % of the points, 2 cm Gaussian noise) with three known changes, the kind
//! a change-detection user looks for:
//!   1. a raised block: the points of a 20 x 20 m square lifted by 2 m;
//!   2. a removed area: the points within 12 m of a centre deleted;
//!   3. an appeared object: an 8 x 8 x 4 m box of new points standing on the ground.
//! Usage: scandiff-make-demo-pair INPUT REFERENCE_OUT COMPARED_OUT [SEED]
//! The changes are placed relative to the input's bounding box, so any
//! airborne or terrestrial scan of a few hundred metres works.

#include <scandiff/core/Error.h>
#include <scandiff/io/FileIO.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <algorithm>
#include <iomanip>
#include <iostream>
#include <random>

int main(int argc, char** argv)
{
    using namespace scandiff;
    if (argc < 4) {
        std::cerr << "usage: scandiff-make-demo-pair INPUT REFERENCE_OUT COMPARED_OUT [SEED]\n";
        return 2;
    }
    try {
        const PluginRegistry registry = makePluginRegistry();
        PointCloud reference = io::readPointCloud(registry.formats, argv[1]);
        const BoundingBox box = reference.bounds();
        const Eigen::Vector3d size = box.max - box.min;
        const auto at = [&](double fx, double fy) { return Eigen::Vector2d(box.min.x() + fx * size.x(), box.min.y() + fy * size.y()); };
        const Eigen::Vector2d blockCorner = at(0.25, 0.2), removedCentre = at(0.7, 0.5), objectCorner = at(0.45, 0.8);
        const double blockSide = 20.0, blockLift = 2.0, removedRadius = 12.0, objectSide = 8.0, objectHeight = 4.0;

        std::mt19937 rng(argc > 4 ? std::stoul(argv[4]) : 2024u);
        std::uniform_real_distribution<double> uniform(0.0, 1.0);
        std::normal_distribution<double> noise(0.0, 0.02);
        std::vector<Eigen::Vector3d> compared;
        std::vector<double> objectGround;
        for (std::size_t i = 0; i < reference.size(); ++i) {
            Eigen::Vector3d p = reference.globalPosition(i);
            const Eigen::Vector2d xy = p.head<2>();
            if ((xy - (objectCorner + Eigen::Vector2d::Constant(objectSide / 2))).norm() < objectSide)
                objectGround.push_back(p.z());
            if ((xy - removedCentre).norm() < removedRadius || uniform(rng) > 0.9)
                continue;
            const Eigen::Vector2d inBlock = xy - blockCorner;
            if (inBlock.x() >= 0 && inBlock.y() >= 0 && inBlock.x() <= blockSide && inBlock.y() <= blockSide)
                p.z() += blockLift;
            compared.push_back(p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
        }
        // The object stands on the ground: the lowest tenth of the heights around it.
        std::sort(objectGround.begin(), objectGround.end());
        const double base = objectGround.empty() ? box.min.z() : objectGround[objectGround.size() / 10];
        const double step = 0.5;
        const auto addFace = [&](const Eigen::Vector3d& origin, const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
            for (double a = 0; a <= u.norm() + 1e-9; a += step)
                for (double b = 0; b <= v.norm() + 1e-9; b += step)
                    compared.push_back(origin + a * u.normalized() + b * v.normalized() +
                                       Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
        };
        const Eigen::Vector3d o(objectCorner.x(), objectCorner.y(), base);
        const Eigen::Vector3d ex(objectSide, 0, 0), ey(0, objectSide, 0), ez(0, 0, objectHeight);
        addFace(o + ez, ex, ey);      // roof
        addFace(o, ex, ez);           // four walls
        addFace(o + ey, ex, ez);
        addFace(o, ey, ez);
        addFace(o + ex, ey, ez);

        PointCloud out;
        out.setOrigin(reference.origin());
        out.resize(compared.size());
        for (std::size_t i = 0; i < compared.size(); ++i)
            out.positions()[i] = (compared[i] - out.origin()).cast<float>();
        io::writePointCloud(registry.formats, reference, argv[2]);
        io::writePointCloud(registry.formats, out, argv[3]);
        std::cout << std::fixed << std::setprecision(2) << "reference " << reference.size() << " points, compared " << out.size() << " points\n"
                  << "raised block: x " << blockCorner.x() << ".." << blockCorner.x() + blockSide << ", y " << blockCorner.y() << ".."
                  << blockCorner.y() + blockSide << ", +" << blockLift << " m\n"
                  << "removed disc: centre " << removedCentre.x() << ", " << removedCentre.y() << ", radius " << removedRadius << " m\n"
                  << "appeared box: x " << objectCorner.x() << ".." << objectCorner.x() + objectSide << ", y " << objectCorner.y() << ".."
                  << objectCorner.y() + objectSide << ", z " << base << ".." << base + objectHeight << '\n';
    } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << '\n';
        return 1;
    }
    return 0;
}
