// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Scoring a shape detection against the truth of a scene, from generic
//! outputs: the detected primitives and, per point, the index of the detected
//! shape it was assigned to (-1: none).
//!
//! Every true shape is matched to the detected shape holding most of its
//! points. Per true shape: the type is right or not, cover = fraction of its
//! points assigned to that detected shape, purity = fraction of that detected
//! shape's points that are this true shape's. A true shape is found when the
//! type is right, cover >= minCover and purity >= minPurity. Only true shapes
//! with at least `requiredPoints` visible points are required (fewer cannot be
//! found, whatever the tool). A detected shape that is no true shape's best
//! match and holds more than `falseShapeMinPoints` points is a false shape.
//! Parameter errors (axis angle, radius, position) are given for information.

#include <scandiff/core/geometry/Primitives.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace scandiff::test::family::primitives {

//! One true shape of a scene, global coordinates.
struct TrueShape
{
    std::string name;
    Primitive primitive;
    std::size_t points = 0; //!< points sampled on it (visible, after occlusion)
    bool required = false;  //!< points >= the scene's requiredPoints
};

struct ScoreOptions
{
    std::size_t requiredPoints = 500; //!< a true shape with fewer points is not required
    //! A detected shape that is no best match counts as false above this many
    //! points; 0: 1 % of the smallest required true shape (at least 1 point).
    std::size_t falseShapeMinPoints = 0;
    double minCover = 0.8;
    double minPurity = 0.9;
};

struct ShapeScore
{
    std::string name;
    PrimitiveKind trueKind = PrimitiveKind::Plane;
    std::size_t truePoints = 0;
    bool required = false;
    int detected = -1;            //!< best-matching detected shape, -1: none holds any of its points
    PrimitiveKind detectedKind = PrimitiveKind::Plane;
    bool typeRight = false;
    double cover = 0;
    double purity = 0;
    bool found = false;           //!< required, type right, cover and purity reached
    bool sharedMatch = false;     //!< another true shape has the same best match
    double axisErrorDeg = std::numeric_limits<double>::quiet_NaN();  //!< normal/axis angle (type right)
    double radiusError = std::numeric_limits<double>::quiet_NaN();   //!< m: radius, torus major; cone: NaN
    double positionError = std::numeric_limits<double>::quiet_NaN(); //!< m: see positionError()
};

struct DetectionScore
{
    std::vector<ShapeScore> shapes;
    std::vector<int> falseShapes;                //!< detected indices
    std::vector<std::size_t> falseShapePoints;   //!< their point counts
    std::size_t required = 0, found = 0, requiredTypeRight = 0, notRequired = 0;
    std::size_t falseShapeMinPoints = 0;         //!< the threshold used

    //! The target: every required shape found, no false shape.
    bool meetsTarget() const { return found == required && falseShapes.empty(); }

    std::string summary() const
    {
        const ShapeScore* worstCover = nullptr;
        const ShapeScore* worstPurity = nullptr;
        for (const ShapeScore& s : shapes) {
            if (!s.required)
                continue;
            if (!worstCover || s.cover < worstCover->cover)
                worstCover = &s;
            if (!worstPurity || s.purity < worstPurity->purity)
                worstPurity = &s;
        }
        char buffer[512];
        std::snprintf(buffer, sizeof buffer,
                      "found %zu/%zu required shapes (type right %zu), %zu false shapes (> %zu points), %zu not required; "
                      "worst cover %.3f (%s), worst purity %.3f (%s)",
                      found, required, requiredTypeRight, falseShapes.size(), falseShapeMinPoints, notRequired,
                      worstCover ? worstCover->cover : 0.0, worstCover ? worstCover->name.c_str() : "-",
                      worstPurity ? worstPurity->purity : 0.0, worstPurity ? worstPurity->name.c_str() : "-");
        return buffer;
    }

    //! One line per true shape, then the false shapes.
    std::string table() const
    {
        std::string out;
        char line[400];
        for (const ShapeScore& s : shapes) {
            std::snprintf(line, sizeof line, "%-28s %-8s %8zu pts %s -> #%-3d %-8s cover %.3f purity %.3f %s axis %.2f deg radius %.4f m pos %.4f m\n",
                          s.name.c_str(), primitiveKindLabel(s.trueKind), s.truePoints, s.required ? "req" : "opt",
                          s.detected, s.detected >= 0 ? primitiveKindLabel(s.detectedKind) : "-", s.cover, s.purity,
                          s.found ? "FOUND" : (s.required ? "MISSED" : "-"), s.axisErrorDeg, s.radiusError, s.positionError);
            out += line;
        }
        for (std::size_t i = 0; i < falseShapes.size(); ++i) {
            std::snprintf(line, sizeof line, "false shape #%d: %zu points\n", falseShapes[i], falseShapePoints[i]);
            out += line;
        }
        return out;
    }

    static const char* primitiveKindLabel(PrimitiveKind k)
    {
        switch (k) {
        case PrimitiveKind::Plane: return "plane";
        case PrimitiveKind::Sphere: return "sphere";
        case PrimitiveKind::Cylinder: return "cylinder";
        case PrimitiveKind::Cone: return "cone";
        case PrimitiveKind::Torus: return "torus";
        }
        return "?";
    }
};

namespace detail {

inline double axisAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, bool oriented)
{
    double c = a.normalized().dot(b.normalized());
    if (!oriented)
        c = std::abs(c);
    return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
}

//! Plane: distance from the true point to the detected plane. Cylinder:
//! distance from the true axis point to the detected axis line. Sphere,
//! torus: between the centres. Cone: between the apexes.
inline double positionError(const Primitive& truth, const Primitive& found)
{
    const Eigen::Vector3d diff = truth.point - found.point;
    switch (truth.kind) {
    case PrimitiveKind::Plane: return std::abs(diff.dot(found.direction.normalized()));
    case PrimitiveKind::Cylinder: {
        const Eigen::Vector3d axis = found.direction.normalized();
        return (diff - diff.dot(axis) * axis).norm();
    }
    default: return diff.norm();
    }
}

inline void fillParameterErrors(ShapeScore& s, const Primitive& truth, const Primitive& found)
{
    if (truth.kind != PrimitiveKind::Sphere)
        s.axisErrorDeg = axisAngleDeg(truth.direction, found.direction, truth.kind == PrimitiveKind::Cone);
    if (truth.kind != PrimitiveKind::Plane && truth.kind != PrimitiveKind::Cone)
        s.radiusError = std::abs(truth.radius - found.radius);
    s.positionError = positionError(truth, found);
}

} // namespace detail

//! `truthLabels[i]`: index in `truth` of point i (-1: clutter).
//! `assignment[i]`: index in `detected` of the shape point i was assigned to (-1: none).
inline DetectionScore scoreDetection(const std::vector<TrueShape>& truth, const std::vector<int>& truthLabels,
                                     const std::vector<Primitive>& detected, const std::vector<int>& assignment,
                                     const ScoreOptions& options)
{
    if (truthLabels.size() != assignment.size())
        throw std::invalid_argument("scoreDetection: one assignment per point is needed");
    const std::size_t nt = truth.size(), nd = detected.size();
    // counts[t * (nd + 1) + d]: points of true shape t (nt: clutter) assigned to detected d (nd: none).
    std::vector<std::size_t> counts((nt + 1) * (nd + 1), 0), detectedSize(nd, 0), trueSize(nt, 0);
    for (std::size_t i = 0; i < assignment.size(); ++i) {
        const int t = truthLabels[i], d = assignment[i];
        if (d < -1 || d >= static_cast<int>(nd) || t < -1 || t >= static_cast<int>(nt))
            throw std::invalid_argument("scoreDetection: label out of range at point " + std::to_string(i));
        const std::size_t tr = t < 0 ? nt : std::size_t(t), dc = d < 0 ? nd : std::size_t(d);
        ++counts[tr * (nd + 1) + dc];
        if (d >= 0)
            ++detectedSize[dc];
        if (t >= 0)
            ++trueSize[tr];
    }
    DetectionScore score;
    std::vector<int> matchCount(nd, 0);
    std::size_t smallestRequired = std::numeric_limits<std::size_t>::max();
    for (std::size_t t = 0; t < nt; ++t) {
        ShapeScore s;
        s.name = truth[t].name;
        s.trueKind = truth[t].primitive.kind;
        s.truePoints = trueSize[t];
        s.required = trueSize[t] >= options.requiredPoints;
        std::size_t best = 0;
        for (std::size_t d = 0; d < nd; ++d)
            if (counts[t * (nd + 1) + d] > best) {
                best = counts[t * (nd + 1) + d];
                s.detected = static_cast<int>(d);
            }
        if (s.detected >= 0) {
            const Primitive& found = detected[std::size_t(s.detected)];
            s.detectedKind = found.kind;
            s.typeRight = found.kind == s.trueKind;
            s.cover = double(best) / double(trueSize[t]);
            s.purity = double(best) / double(detectedSize[std::size_t(s.detected)]);
            ++matchCount[std::size_t(s.detected)];
            if (s.typeRight)
                detail::fillParameterErrors(s, truth[t].primitive, found);
        }
        s.found = s.required && s.typeRight && s.cover >= options.minCover && s.purity >= options.minPurity;
        if (s.required) {
            ++score.required;
            score.found += s.found ? 1 : 0;
            score.requiredTypeRight += s.typeRight ? 1 : 0;
            smallestRequired = std::min(smallestRequired, trueSize[t]);
        } else {
            ++score.notRequired;
        }
        score.shapes.push_back(s);
    }
    for (ShapeScore& s : score.shapes)
        s.sharedMatch = s.detected >= 0 && matchCount[std::size_t(s.detected)] > 1;
    score.falseShapeMinPoints = options.falseShapeMinPoints > 0 ? options.falseShapeMinPoints
                                : smallestRequired == std::numeric_limits<std::size_t>::max()
                                    ? 1
                                    : std::max<std::size_t>(1, smallestRequired / 100);
    for (std::size_t d = 0; d < nd; ++d)
        if (matchCount[d] == 0 && detectedSize[d] > score.falseShapeMinPoints) {
            score.falseShapes.push_back(static_cast<int>(d));
            score.falseShapePoints.push_back(detectedSize[d]);
        }
    return score;
}

} // namespace scandiff::test::family::primitives
