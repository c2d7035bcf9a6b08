// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Analytic scenes for primitive extraction: known planes (a box's sides, a
//! wall with a panel 10 cm in front of it, two coplanar plates apart),
//! cylinders, a sphere, a cone and a torus, sampled at random in proportion
//! to area, with Gaussian noise along the surface normal and uniform clutter.
//! Every point knows the shape it was drawn on (-1 for clutter).
//! Header-only: the tests and bench/MakeSyntheticScan.cpp both use it.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/geometry/Primitives.h>

#include <Eigen/Geometry>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

namespace scandiff::test {

struct SceneShape
{
    Primitive truth;
    std::string label;
    double area = 0;
    //! A point of the shape and its unit normal from two uniforms in [0, 1).
    std::function<void(double, double, std::mt19937_64&, Eigen::Vector3d&, Eigen::Vector3d&)> sample;
};

struct PrimitiveScene
{
    PointCloud cloud;
    std::vector<SceneShape> shapes;
    std::vector<int> truth; //!< per point: its shape's index, -1 for clutter
};

namespace scene {

constexpr double kPi = 3.14159265358979323846;

inline void frame(const Eigen::Vector3d& d, Eigen::Vector3d& e1, Eigen::Vector3d& e2)
{
    const Eigen::Vector3d helper = std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    e1 = (helper - helper.dot(d) * d).normalized();
    e2 = d.cross(e1);
}

//! A rectangle from a corner and two orthogonal edges.
inline SceneShape rectangle(const std::string& label, const Eigen::Vector3d& corner, const Eigen::Vector3d& u, const Eigen::Vector3d& v)
{
    SceneShape s;
    s.label = label;
    s.area = u.cross(v).norm();
    s.truth.kind = PrimitiveKind::Plane;
    s.truth.point = corner;
    s.truth.direction = u.cross(v).normalized();
    const Eigen::Vector3d n = s.truth.direction;
    s.sample = [=](double a, double b, std::mt19937_64&, Eigen::Vector3d& p, Eigen::Vector3d& normal) {
        p = corner + a * u + b * v;
        normal = n;
    };
    return s;
}

inline SceneShape cylinder(const std::string& label, const Eigen::Vector3d& base, const Eigen::Vector3d& axis, double radius, double length)
{
    SceneShape s;
    s.label = label;
    s.area = 2 * kPi * radius * length;
    s.truth.kind = PrimitiveKind::Cylinder;
    s.truth.point = base;
    s.truth.direction = axis.normalized();
    s.truth.radius = radius;
    Eigen::Vector3d e1, e2;
    frame(s.truth.direction, e1, e2);
    const Eigen::Vector3d d = s.truth.direction;
    s.sample = [=](double a, double b, std::mt19937_64&, Eigen::Vector3d& p, Eigen::Vector3d& normal) {
        normal = std::cos(2 * kPi * a) * e1 + std::sin(2 * kPi * a) * e2;
        p = base + b * length * d + radius * normal;
    };
    return s;
}

inline SceneShape sphere(const std::string& label, const Eigen::Vector3d& centre, double radius)
{
    SceneShape s;
    s.label = label;
    s.area = 4 * kPi * radius * radius;
    s.truth.kind = PrimitiveKind::Sphere;
    s.truth.point = centre;
    s.truth.radius = radius;
    s.sample = [=](double a, double b, std::mt19937_64&, Eigen::Vector3d& p, Eigen::Vector3d& normal) {
        const double z = 2 * a - 1, phi = 2 * kPi * b, r = std::sqrt(1 - z * z);
        normal = Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
        p = centre + radius * normal;
    };
    return s;
}

//! A cone from its apex, between distances h0 and h1 along the axis.
inline SceneShape cone(const std::string& label, const Eigen::Vector3d& apex, const Eigen::Vector3d& axis, double halfAngle, double h0, double h1)
{
    SceneShape s;
    s.label = label;
    s.area = kPi * std::tan(halfAngle) / std::cos(halfAngle) * (h1 * h1 - h0 * h0);
    s.truth.kind = PrimitiveKind::Cone;
    s.truth.point = apex;
    s.truth.direction = axis.normalized();
    s.truth.halfAngle = halfAngle;
    Eigen::Vector3d e1, e2;
    frame(s.truth.direction, e1, e2);
    const Eigen::Vector3d d = s.truth.direction;
    s.sample = [=](double a, double b, std::mt19937_64&, Eigen::Vector3d& p, Eigen::Vector3d& normal) {
        const double h = std::sqrt(h0 * h0 + a * (h1 * h1 - h0 * h0)); // area grows with h
        const Eigen::Vector3d radial = std::cos(2 * kPi * b) * e1 + std::sin(2 * kPi * b) * e2;
        p = apex + h * d + h * std::tan(halfAngle) * radial;
        normal = (std::cos(halfAngle) * radial - std::sin(halfAngle) * d).normalized();
    };
    return s;
}

inline SceneShape torus(const std::string& label, const Eigen::Vector3d& centre, const Eigen::Vector3d& axis, double major, double minor)
{
    SceneShape s;
    s.label = label;
    s.area = 4 * kPi * kPi * major * minor;
    s.truth.kind = PrimitiveKind::Torus;
    s.truth.point = centre;
    s.truth.direction = axis.normalized();
    s.truth.radius = major;
    s.truth.minorRadius = minor;
    Eigen::Vector3d e1, e2;
    frame(s.truth.direction, e1, e2);
    const Eigen::Vector3d d = s.truth.direction;
    s.sample = [=](double a, double, std::mt19937_64& rng, Eigen::Vector3d& p, Eigen::Vector3d& normal) {
        // The tube's angle v drawn in proportion to the area (major + minor cos v).
        std::uniform_real_distribution<double> uniform(0, 1);
        double v = 0;
        do
            v = 2 * kPi * uniform(rng);
        while (uniform(rng) * (major + minor) > major + minor * std::cos(v));
        const Eigen::Vector3d radial = std::cos(2 * kPi * a) * e1 + std::sin(2 * kPi * a) * e2;
        normal = std::cos(v) * radial + std::sin(v) * d;
        p = centre + major * radial + minor * normal;
    };
    return s;
}

} // namespace scene

//! The shapes of the test scene, in a 12 x 12 x 4 m box: a ground, a wall
//! and a panel 10 cm in front of it, two coplanar plates 1 m apart, a box
//! (its 5 visible sides), a vertical and a horizontal cylinder, a sphere, a
//! cone and a torus; each well apart from the others.
inline std::vector<SceneShape> testSceneShapes()
{
    using namespace scene;
    using V = Eigen::Vector3d;
    std::vector<SceneShape> s;
    s.push_back(rectangle("ground", V(0, 0, 0), V(12, 0, 0), V(0, 12, 0)));
    s.push_back(rectangle("wall", V(0.0, 1, 0.3), V(0, 0, 3), V(0, 8, 0)));
    s.push_back(rectangle("panel", V(0.1, 3, 0.8), V(0, 0, 1.5), V(0, 3, 0)));
    s.push_back(rectangle("plate A", V(3, 9.5, 1.2), V(1.5, 0, 0), V(0, 1.5, 0)));
    s.push_back(rectangle("plate B", V(5.5, 9.5, 1.2), V(1.5, 0, 0), V(0, 1.5, 0)));
    // A box of 1.2 m on a 0.3 m gap above the ground: its top and four sides.
    const V b(8, 8, 0.3);
    const double w = 1.2;
    s.push_back(rectangle("box top", b + V(0, 0, w), V(w, 0, 0), V(0, w, 0)));
    s.push_back(rectangle("box -x", b, V(0, w, 0), V(0, 0, w)));
    s.push_back(rectangle("box +x", b + V(w, 0, 0), V(0, 0, w), V(0, w, 0)));
    s.push_back(rectangle("box -y", b, V(0, 0, w), V(w, 0, 0)));
    s.push_back(rectangle("box +y", b + V(0, w, 0), V(w, 0, 0), V(0, 0, w)));
    s.push_back(cylinder("column", V(4, 4, 0.2), V(0, 0, 1), 0.3, 3.0));
    s.push_back(cylinder("pipe", V(6, 2, 1.5), V(1, 0.2, 0), 0.15, 3.5));
    s.push_back(sphere("sphere", V(3, 7, 1.5), 0.5));
    s.push_back(cone("cone", V(10.5, 4.5, 2.5), V(0, 0, -1), 25.0 * scene::kPi / 180.0, 0.3, 1.8));
    s.push_back(torus("torus", V(6.5, 5.5, 1.0), V(0, 0, 1), 0.6, 0.15));
    return s;
}

//! A façade after thesis 001's scenes, turned by `azimuth` (radians) about
//! the vertical: a 12 x 8 m wall with four windows, each window's glass 15 cm
//! behind the wall (four disjoint coplanar plates), a sign 10 cm in front of
//! the wall, a cornice and a string course (horizontal), two pilasters' sides
//! across the façade, and a roof slope (inclined). The wall is shapes[0];
//! the façade's outward normal is (-sin a, cos a, 0).
inline std::vector<SceneShape> facadeSceneShapes(double azimuth, const Eigen::Vector3d& at)
{
    const Eigen::Vector3d along(std::cos(azimuth), std::sin(azimuth), 0), out(-std::sin(azimuth), std::cos(azimuth), 0),
        up = Eigen::Vector3d::UnitZ();
    struct Window
    {
        double x, z;
    };
    const std::vector<Window> windows = {{1.5, 1.0}, {4.5, 1.0}, {7.5, 1.0}, {1.5, 4.5}};
    const double width = 1.2, height = 1.6;
    std::vector<SceneShape> shapes;
    // The wall: a rectangle sampled outside its windows (drawn again inside one).
    SceneShape wall = scene::rectangle("wall", at, 12 * along, 8 * up);
    wall.area = 96.0 - windows.size() * width * height;
    wall.sample = [=](double a, double b, std::mt19937_64& rng, Eigen::Vector3d& p, Eigen::Vector3d& normal) {
        std::uniform_real_distribution<double> uniform(0, 1);
        for (;;) {
            const double x = 12 * a, z = 8 * b;
            bool inside = false;
            for (const Window& w : windows)
                inside = inside || (x > w.x && x < w.x + width && z > w.z && z < w.z + height);
            if (!inside) {
                p = at + x * along + z * up;
                normal = out;
                return;
            }
            a = uniform(rng);
            b = uniform(rng);
        }
    };
    shapes.push_back(wall);
    for (std::size_t k = 0; k < windows.size(); ++k)
        shapes.push_back(scene::rectangle("glass " + std::to_string(k), at + windows[k].x * along + windows[k].z * up - 0.15 * out,
                                   width * along, height * up));
    shapes.push_back(scene::rectangle("sign", at + 9.5 * along + 1.5 * up + 0.10 * out, 2.0 * along, 1.0 * up));
    shapes.push_back(scene::rectangle("cornice", at + 8.0 * up, 12 * along, 0.4 * out));
    shapes.push_back(scene::rectangle("string course", at + 3.2 * up, 12 * along, 0.2 * out));
    shapes.push_back(scene::rectangle("pilaster left", at + 0.3 * along, 0.3 * out, 8 * up));
    shapes.push_back(scene::rectangle("pilaster right", at + 11.7 * along, 0.3 * out, 8 * up));
    shapes.push_back(scene::rectangle("roof", at + 8.0 * up - 0.5 * out, 12 * along, -3.0 * out + 2.0 * up));
    return shapes;
}

//! Samples `shapes` with `points` points in all (a share `clutter` of them
//! uniform in the box around the scene), noise along the normals, and sets
//! the cloud's exact normals when asked.
inline PrimitiveScene makePrimitiveScene(const std::vector<SceneShape>& shapes, std::size_t points, double noise, double clutter,
                                         unsigned seed, bool withNormals)
{
    PrimitiveScene scene;
    scene.shapes = shapes;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uniform(0, 1);
    std::normal_distribution<double> gauss(0, noise);
    double total = 0;
    for (const SceneShape& s : shapes)
        total += s.area;
    const std::size_t clutterPoints = static_cast<std::size_t>(clutter * static_cast<double>(points));
    std::vector<Eigen::Vector3d> positions, normals;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (std::size_t k = 0; k < shapes.size(); ++k) {
        const auto count = static_cast<std::size_t>(std::llround(shapes[k].area / total * static_cast<double>(points - clutterPoints)));
        for (std::size_t i = 0; i < count; ++i) {
            Eigen::Vector3d p, n;
            const double a = uniform(rng), b = uniform(rng);
            shapes[k].sample(a, b, rng, p, n);
            p += gauss(rng) * n;
            positions.push_back(p);
            normals.push_back(n);
            scene.truth.push_back(static_cast<int>(k));
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
    }
    for (std::size_t i = 0; i < clutterPoints; ++i) {
        const Eigen::Vector3d p = lo + Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)).cwiseProduct(hi - lo);
        positions.push_back(p);
        normals.push_back(Eigen::Vector3d(uniform(rng) - 0.5, uniform(rng) - 0.5, uniform(rng) - 0.5).normalized());
        scene.truth.push_back(-1);
    }
    scene.cloud.resize(positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i)
        scene.cloud.positions()[i] = positions[i].cast<float>();
    if (withNormals) {
        auto& n = scene.cloud.enableNormals();
        for (std::size_t i = 0; i < positions.size(); ++i)
            n[i] = normals[i].cast<float>();
    }
    scene.cloud.name = "primitive-scene";
    return scene;
}

} // namespace scandiff::test
