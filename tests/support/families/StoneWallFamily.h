// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Family "ashlar stone wall with tight joints": a masonry wall scanned from
//! one levelled terrestrial station, for tools that draw the wall stone by
//! stone from the points' intensity (and possibly relief). Conditions after
//! Boucher (2015, seed 003): stone-by-stone surveys of historic walls at
//! 5 mm-1 cm spacing, stones told from joints by laser intensity (either
//! polarity), isolated joint-coloured points on stones, 3 cm tolerance.
//!
//! The scene:
//! - ashlar in running bond: courses of rectangular stones separated by
//!   joints `jointWidth` wide, recessed `jointRecess` behind the stone faces
//!   (0: flush, intensity only); vertical joints of neighbouring courses at
//!   least `bondMinOverlap` apart (halved when a narrow width range cannot
//!   give it); the panel is cropped along the joint centrelines around it,
//!   so every stone is whole;
//! - stone faces slightly uneven: a bulge of `bulgeMin`-`bulgeMax` and a
//!   setting offset (sigma `faceOffsetSigma`) per stone;
//! - a TLS at `stationDistance`, sweeping a yaw/pitch grid whose step gives the
//!   median spacing `spacing` on the face; the beam falls into the joint
//!   grooves, so it hits groove bottoms, or the stones' arrises (sides) when the
//!   groove is seen obliquely; range noise along the ray;
//! - intensity (scalar field `intensity`): stone level (+ a per-stone tint)
//!   and joint level, Gaussian noise, a mild fall-off with incidence angle;
//!   the beam footprint (`beamRadius`) straddling a joint edge mixes the
//!   levels (and the ranges) of stone and joint, as real returns do;
//!   `darkPoints` stone points take the joint level (isolated), and
//!   `darkPatches` discs (1-3 cm) of soiling on stones do too.
//! Truth: each stone's face rectangle in the wall frame, and per point the
//! stone id (-1 for joint points; points on a stone's arris belong to it).
//!
//! Issue case: 16 courses x 20 stones (320), 30-50 cm x 24 cm, joints 12 mm,
//! recessed 8 mm, stones ~1400 and joints ~800 (contrast 600, sigma 120), 17
//! dark points, 5 mm spacing (~1.3 M points), 3 mm noise, 1-3 mm bulges,
//! Lambert-93, vertical, random heading.
//! Family: joints 5-25 mm wide, recess 0 (a quarter of draws) or 0-15 mm,
//! spacing 2 mm-2 cm but at most the joint width, contrast 3-10 sigma (sigma
//! 40-200, levels anywhere in a signed range -1500..1500), either polarity,
//! noise 1-5 mm, stones 20-80 cm wide (a draw's range 10-30 cm wide),
//! courses 15-40 cm high (equal or varying by up to +-6 cm), 4-20 courses x
//! 6-25 stones at full size (caps shrink with sqrt(scale): 4-6 x 6-9 at
//! 0.05), dark points (0-0.15 per stone) and, in half of the draws, dark
//! patches; lean 0 or up to +-1 deg; panel base 0-3 m above
//! the scanner's ground. `scale` < 1 removes stones then courses (down to
//! 4 courses x 6 stones) until the ray count fits 6e6 * scale (at least
//! 2e5), then coarsens the spacing (never beyond the joint width or 2 cm).
//!
//! Scoring: for each true stone the detected polygon with best IoU; a stone is
//! right when exactly one polygon has IoU >= 0.8 with it and that polygon's
//! symmetric boundary Hausdorff distance is <= 3 cm. False polygons: detected
//! polygons with IoU < 0.5 against every stone (fraction of detected).
//! Issue target: >= 98 % right, <= 2 % false. Per-point labels are scored
//! too (Boucher's P1-P4 for stone/joint and the share of stone points whose
//! segment maps to their own stone).

#include "WallSurveyCommon.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace scandiff::test::family::stonewall {

// Using-declarations, not a using-directive: other families declare helpers
// of the same names (gaussian, kPi...) in scandiff::test::family, and names
// declared here are found first, so including several families stays unambiguous.
using wallsurvey::Box2;
using wallsurvey::boundaryHausdorff;
using wallsurvey::boxOf;
using wallsurvey::directedHausdorff;
using wallsurvey::drawProjectedCorner;
using wallsurvey::format;
using wallsurvey::gaussian;
using wallsurvey::kInf;
using wallsurvey::kPi;
using wallsurvey::logUniform;
using wallsurvey::makeCloud;
using wallsurvey::makeScanGrid;
using wallsurvey::makeWallFrame;
using wallsurvey::openRing;
using wallsurvey::Overlap;
using wallsurvey::Polygon2;
using wallsurvey::polygonArea;
using wallsurvey::polygonOverlap;
using wallsurvey::projectRing;
using wallsurvey::Ring3;
using wallsurvey::ScanGrid;
using wallsurvey::sensorPose;
using wallsurvey::uniform;
using wallsurvey::WallFrame;

struct StoneWallParams
{
    int courses = 16;                    //!< number of courses
    int stonesPerCourse = 20;            //!< stones in each course
    double stoneWidthMin = 0.30;         //!< m, face width range of a stone
    double stoneWidthMax = 0.50;
    std::vector<double> courseHeights;   //!< m, face height per course (bottom first); empty: all courseHeight
    double courseHeight = 0.24;          //!< m
    double jointWidth = 0.012;           //!< m
    double jointRecess = 0.008;          //!< m behind the stone faces (0: flush)
    double bondMinOverlap = 0.08;        //!< m, least distance between vertical joints of adjacent courses
    double bulgeMin = 0.001, bulgeMax = 0.003; //!< m, bulge of a stone face at its centre
    double faceOffsetSigma = 0.0005;     //!< m, setting offset of each stone's face

    double spacing = 0.005;              //!< median point spacing on the face (m)
    double rangeNoise = 0.003;           //!< m, standard deviation along the ray
    double beamRadius = 0.002;           //!< m, footprint radius (mixes stone and joint at edges)
    double stationDistance = 6.0;        //!< m, horizontal distance from the face
    double stationAlongFraction = 0.5;   //!< scanner position along the wall, fraction of its width
    double stationHeight = 1.6;          //!< m, scanner centre above its ground
    double wallBase = 0.5;               //!< m, panel bottom above the scanner's ground

    double stoneIntensity = 1400.0;      //!< mean intensity of stone faces
    double jointIntensity = 800.0;       //!< mean intensity of joints
    double intensityNoise = 120.0;       //!< standard deviation per point
    double stoneTint = 36.0;             //!< standard deviation of a stone's own mean around stoneIntensity
    double incidenceFalloff = 300.0;     //!< intensity lost per unit of (1 - cos incidence)
    int darkPoints = 17;                 //!< isolated stone points at the joint level
    int darkPatches = 0;                 //!< discs of joint-level soiling on stones
    double darkPatchRadiusMin = 0.01, darkPatchRadiusMax = 0.03; //!< m

    double headingDeg = 123.0;           //!< azimuth of u, counter-clockwise from east (deg)
    double tiltDeg = 0.0;                //!< lean from vertical, + towards the scanner (deg)
    Eigen::Vector3d corner{672345.678, 6843210.987, 87.65}; //!< global bottom-left corner of the panel (Lambert-93)
    std::uint64_t seed = 1;              //!< layout, noise, dark spots
};

struct Stone
{
    int course = 0;
    double x0 = 0, y0 = 0, x1 = 0, y1 = 0; //!< face rectangle, wall 2D (m)
    double tint = 0, bulge = 0, offset = 0;
};

struct DarkPatch
{
    int stone = 0;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    double radius = 0.0;
};

//! Where a point's beam centre fell (truth).
enum class StonePart : std::uint8_t { Face, Arris, Joint };

struct StoneWallScene
{
    StoneWallParams params;
    WallFrame frame;                      //!< origin = bottom-left corner of the panel
    double width = 0.0, height = 0.0;     //!< panel size (m), joint centreline to joint centreline
    std::vector<Stone> stones;            //!< id = index; course by course, bottom first, left to right
    std::vector<Polygon2> stoneTruth;     //!< face rectangles, counter-clockwise, wall 2D
    std::vector<double> courseCuts;       //!< joint centrelines between courses (courses + 1 values)
    std::vector<std::vector<double>> jointCuts; //!< per course, vertical joint centrelines (stones + 1 values)
    std::vector<DarkPatch> patches;
    PointCloud cloud;                     //!< with field "intensity" and one sensor pose
    std::vector<int> stoneId;             //!< per point: stone id, -1 on a joint
    std::vector<StonePart> part;          //!< per point: stone face, stone side inside a groove, or joint
    std::vector<std::size_t> darkPointIndices;
    ScanGrid scanner;
};

// ------------------------------------------------------------------ layout

inline double courseHeightOf(const StoneWallParams& p, int c)
{
    return p.courseHeights.empty() ? p.courseHeight : p.courseHeights[static_cast<std::size_t>(c)];
}

inline double meanStoneWidth(const StoneWallParams& p) { return 0.5 * (p.stoneWidthMin + p.stoneWidthMax); }

//! Widths of one course's stones summing to `total`, each in [wmin, wmax],
//! keeping every inner joint `overlap` away from the previous course's
//! joints. Empty when this attempt dead-ends.
inline std::vector<double> drawCourse(const StoneWallParams& p, const std::vector<double>& below, double overlap,
                                      SplitMix64& rng)
{
    const int n = p.stonesPerCourse;
    const double j = p.jointWidth, wmin = p.stoneWidthMin, wmax = p.stoneWidthMax;
    double remaining = n * meanStoneWidth(p), left = 0.0; // left: joint centreline at the stone's left
    std::vector<double> widths;
    for (int k = 0; k < n; ++k) {
        const int after = n - 1 - k;
        if (after == 0) {
            widths.push_back(remaining);
            return widths;
        }
        const double lo = std::max(wmin, remaining - after * wmax), hi = std::min(wmax, remaining - after * wmin);
        std::vector<std::pair<double, double>> allowed{{lo, hi}};
        for (std::size_t b = 1; b + 1 < below.size(); ++b) { // the joint would sit at left + w + j
            const double fLo = below[b] - overlap - left - j, fHi = below[b] + overlap - left - j;
            std::vector<std::pair<double, double>> next;
            for (const auto& a : allowed) {
                if (a.first < fLo) next.push_back({a.first, std::min(a.second, fLo)});
                if (a.second > fHi) next.push_back({std::max(a.first, fHi), a.second});
            }
            allowed.swap(next);
        }
        double length = 0.0;
        for (const auto& a : allowed)
            length += std::max(0.0, a.second - a.first);
        if (!(length > 1e-6))
            return {};
        double pick = rng.uniform() * length, w = allowed.back().second;
        for (const auto& a : allowed) {
            const double l = std::max(0.0, a.second - a.first);
            if (pick <= l) {
                w = a.first + pick;
                break;
            }
            pick -= l;
        }
        widths.push_back(w);
        remaining -= w;
        left += w + j;
    }
    return widths;
}

//! Stones, cuts and dark patches of the wall (a pure function of params).
inline void buildLayout(StoneWallScene& s)
{
    const StoneWallParams& p = s.params;
    SplitMix64 rng(p.seed, 0x57011E);
    const double j = p.jointWidth;
    s.width = p.stonesPerCourse * (meanStoneWidth(p) + j);
    s.courseCuts = {0.0};
    std::vector<double> below; // previous course's joint centrelines
    for (int c = 0; c < p.courses; ++c) {
        const double h = courseHeightOf(p, c), y0 = s.courseCuts.back();
        std::vector<double> widths;
        double overlap = p.bondMinOverlap;
        for (int attempt = 1; widths.empty(); ++attempt) {
            widths = drawCourse(p, below, overlap, rng);
            if (attempt % 200 == 0)
                overlap *= 0.5; // a narrow width range may not allow the asked lap
        }
        std::vector<double> cuts{0.0};
        for (double w : widths) {
            Stone st;
            st.course = c;
            st.x0 = cuts.back() + 0.5 * j, st.x1 = st.x0 + w;
            st.y0 = y0 + 0.5 * j, st.y1 = st.y0 + h;
            st.tint = p.stoneTint * gaussian(rng);
            st.bulge = uniform(rng, p.bulgeMin, p.bulgeMax);
            st.offset = p.faceOffsetSigma * gaussian(rng);
            s.stones.push_back(st);
            cuts.push_back(cuts.back() + w + j);
        }
        cuts.back() = s.width; // remove rounding drift
        s.jointCuts.push_back(cuts);
        below = cuts;
        s.courseCuts.push_back(y0 + h + j);
    }
    s.height = s.courseCuts.back();
    for (const auto& st : s.stones)
        s.stoneTruth.push_back({{st.x0, st.y0}, {st.x1, st.y0}, {st.x1, st.y1}, {st.x0, st.y1}});
    for (int k = 0; k < p.darkPatches; ++k) {
        DarkPatch d;
        d.stone = static_cast<int>(rng.below(s.stones.size()));
        const Stone& st = s.stones[static_cast<std::size_t>(d.stone)];
        d.radius = std::min(uniform(rng, p.darkPatchRadiusMin, p.darkPatchRadiusMax), 0.3 * (st.y1 - st.y0));
        d.centre = {uniform(rng, st.x0 + 1.5 * d.radius, st.x1 - 1.5 * d.radius),
                    uniform(rng, st.y0 + 1.5 * d.radius, st.y1 - 1.5 * d.radius)};
        s.patches.push_back(d);
    }
}

//! The stone whose face contains q, or -1 (a joint, or outside).
inline int stoneAt(const StoneWallScene& s, const Eigen::Vector2d& q)
{
    if (q.y() < 0 || q.y() > s.height || q.x() < 0 || q.x() > s.width)
        return -1;
    const auto cy = std::upper_bound(s.courseCuts.begin(), s.courseCuts.end(), q.y());
    const int c = std::clamp(static_cast<int>(cy - s.courseCuts.begin()) - 1, 0, s.params.courses - 1);
    const auto& cuts = s.jointCuts[static_cast<std::size_t>(c)];
    const int k = std::clamp(static_cast<int>(std::upper_bound(cuts.begin(), cuts.end(), q.x()) - cuts.begin()) - 1, 0,
                             s.params.stonesPerCourse - 1);
    const int id = c * s.params.stonesPerCourse + k;
    const Stone& st = s.stones[static_cast<std::size_t>(id)];
    return q.x() >= st.x0 && q.x() <= st.x1 && q.y() >= st.y0 && q.y() <= st.y1 ? id : -1;
}

inline double faceHeight(const Stone& st, const Eigen::Vector2d& q)
{
    const double xi = (2.0 * q.x() - st.x0 - st.x1) / (st.x1 - st.x0), eta = (2.0 * q.y() - st.y0 - st.y1) / (st.y1 - st.y0);
    return st.offset + st.bulge * std::max(0.0, 1.0 - xi * xi) * std::max(0.0, 1.0 - eta * eta);
}

//! Share of a disc of radius r whose centre is e from a straight edge lying on the far side of that edge.
inline double discShareBeyond(double e, double r)
{
    if (e >= r)
        return 0.0;
    return (r * r * std::acos(e / r) - e * std::sqrt(r * r - e * e)) / (kPi * r * r);
}

inline double distanceToRect(const Stone& st, const Eigen::Vector2d& q)
{
    const double dx = std::max({st.x0 - q.x(), 0.0, q.x() - st.x1}), dy = std::max({st.y0 - q.y(), 0.0, q.y() - st.y1});
    return std::hypot(dx, dy);
}

struct StoneHit
{
    double t = kInf;
    int stone = -1;        //!< surface at the beam centre (-1: joint)
    double stoneShare = 1; //!< share of the footprint on stone
    double cosIncidence = 1;
    bool arris = false;    //!< on a stone's side inside a groove
    Eigen::Vector2d q = Eigen::Vector2d::Zero(); //!< wall 2D position
};

//! Nearest stone faces around q: its course's and the neighbouring courses' stones near x.
inline std::vector<int> stonesNear(const StoneWallScene& s, const Eigen::Vector2d& q, double reach)
{
    std::vector<int> out;
    const int nc = s.params.courses, ns = s.params.stonesPerCourse;
    const auto above = std::upper_bound(s.courseCuts.begin(), s.courseCuts.end(), q.y());
    const int c = std::clamp(static_cast<int>(above - s.courseCuts.begin()) - 1, 0, nc - 1);
    for (int cc = std::max(0, c - 1); cc <= std::min(nc - 1, c + 1); ++cc)
        for (int k = 0; k < ns; ++k) {
            const int id = cc * ns + k;
            if (distanceToRect(s.stones[static_cast<std::size_t>(id)], q) <= reach)
                out.push_back(id);
        }
    return out;
}

//! Casts one ray (wall coordinates) onto the masonry: stone faces with their
//! bulge, groove bottoms, or the stones' sides inside the grooves.
inline bool castRay(const StoneWallScene& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d, StoneHit& hit)
{
    if (d.z() >= 0.0)
        return false;
    const StoneWallParams& p = s.params;
    const double t0 = -o.z() / d.z();
    const Eigen::Vector2d q0(o.x() + t0 * d.x(), o.y() + t0 * d.y());
    if (q0.x() < 0 || q0.x() > s.width || q0.y() < 0 || q0.y() > s.height)
        return false; // cropped: the extract ends on joint centrelines
    const double r = p.beamRadius;
    const int id = stoneAt(s, q0);
    hit = StoneHit{};
    if (id >= 0) {
        const Stone& st = s.stones[static_cast<std::size_t>(id)];
        double t = t0;
        for (int it = 0; it < 3; ++it) // fixed point onto the slightly bulging face
            t = (faceHeight(st, {o.x() + t * d.x(), o.y() + t * d.y()}) - o.z()) / d.z();
        hit.t = t, hit.stone = id, hit.q = {o.x() + t * d.x(), o.y() + t * d.y()};
        const double e = std::min({hit.q.x() - st.x0, st.x1 - hit.q.x(), hit.q.y() - st.y0, st.y1 - hit.q.y()});
        hit.stoneShare = 1.0 - discShareBeyond(std::max(0.0, e), r);
        hit.cosIncidence = -d.z();
        hit.t += (1.0 - hit.stoneShare) * p.jointRecess / -d.z(); // part of the footprint in the groove
        return true;
    }
    const std::vector<int> near = stonesNear(s, q0, p.jointWidth + p.jointRecess + r);
    const double t1 = (-p.jointRecess - o.z()) / d.z();
    const Eigen::Vector2d step(d.x() * (t1 - t0), d.y() * (t1 - t0)); // path across the groove
    double enter = kInf;
    Eigen::Vector2d sideNormal = Eigen::Vector2d::Zero();
    int sideStone = -1;
    for (int k : near) { // slab entry of the 2D path into each stone's block
        const Stone& st = s.stones[static_cast<std::size_t>(k)];
        double lo = 0.0, hi = 1.0;
        Eigen::Vector2d nrm = Eigen::Vector2d::Zero();
        bool ok = true;
        for (int a = 0; a < 2 && ok; ++a) {
            const double mn = a == 0 ? st.x0 : st.y0, mx = a == 0 ? st.x1 : st.y1;
            if (std::abs(step[a]) < 1e-15) {
                ok = q0[a] >= mn && q0[a] <= mx;
                continue;
            }
            double e1 = (mn - q0[a]) / step[a], e2 = (mx - q0[a]) / step[a];
            const double sign = e1 < e2 ? -1.0 : 1.0; // normal of the side entered
            if (e1 > e2)
                std::swap(e1, e2);
            if (e1 > lo)
                lo = e1, nrm = Eigen::Vector2d::Zero(), nrm[a] = sign;
            hi = std::min(hi, e2);
            ok = lo <= hi;
        }
        if (ok && lo < enter)
            enter = lo, sideStone = k, sideNormal = nrm;
    }
    if (p.jointRecess > 0.0 && sideStone >= 0 && enter < 1.0) { // the beam meets a stone's arris
        hit.t = t0 + enter * (t1 - t0), hit.stone = sideStone, hit.stoneShare = 1.0, hit.arris = true;
        hit.q = q0 + enter * step;
        hit.cosIncidence = std::abs(d.x() * sideNormal.x() + d.y() * sideNormal.y());
        return true;
    }
    hit.t = p.jointRecess > 0.0 ? t1 : t0;
    hit.q = {o.x() + hit.t * d.x(), o.y() + hit.t * d.y()};
    double e = kInf;
    for (int k : near)
        e = std::min(e, distanceToRect(s.stones[static_cast<std::size_t>(k)], hit.q));
    hit.stoneShare = discShareBeyond(e, r);
    hit.cosIncidence = -d.z();
    hit.t -= hit.stoneShare * p.jointRecess / -d.z(); // part of the footprint on the stone faces
    return true;
}

inline Eigen::Vector3d stationInWall(const StoneWallParams& p, const WallFrame& frame, double width)
{
    return Eigen::Vector3d(p.stationAlongFraction * width, 0, 0) + (p.stationHeight - p.wallBase) * frame.upInWall() +
           p.stationDistance * frame.outwardInWall();
}

inline double panelWidth(const StoneWallParams& p) { return p.stonesPerCourse * (meanStoneWidth(p) + p.jointWidth); }
inline double panelHeight(const StoneWallParams& p)
{
    double h = 0.0;
    for (int c = 0; c < p.courses; ++c)
        h += courseHeightOf(p, c) + p.jointWidth;
    return h;
}

inline ScanGrid scanGridFor(const StoneWallParams& p, const WallFrame& frame)
{
    const double w = panelWidth(p), h = panelHeight(p);
    return makeScanGrid(frame, stationInWall(p, frame, w), 0.0, w, 0.0, h, p.spacing);
}

inline StoneWallScene make(const StoneWallParams& p)
{
    StoneWallScene s;
    s.params = p;
    s.frame = makeWallFrame(p.corner, p.headingDeg, p.tiltDeg);
    buildLayout(s);
    std::vector<std::vector<int>> patchesOf(s.stones.size());
    for (std::size_t k = 0; k < s.patches.size(); ++k)
        patchesOf[static_cast<std::size_t>(s.patches[k].stone)].push_back(static_cast<int>(k));
    s.scanner = scanGridFor(p, s.frame);
    const Eigen::Vector3d o = s.scanner.position;
    std::vector<Eigen::Vector3d> global;
    std::vector<float> intensity;
    std::vector<std::size_t> pureStonePoints; // candidates for isolated dark points
    s.scanner.sweep([&](const Eigen::Vector3d& d, std::size_t ray) {
        StoneHit hit;
        if (!castRay(s, o, d, hit))
            return;
        SplitMix64 rng(p.seed, ray);
        global.push_back(s.frame.toGlobal(o + (hit.t + p.rangeNoise * gaussian(rng)) * d));
        double stoneLevel = p.jointIntensity;
        if (hit.stone >= 0) {
            stoneLevel = p.stoneIntensity + s.stones[static_cast<std::size_t>(hit.stone)].tint;
            for (int k : patchesOf[static_cast<std::size_t>(hit.stone)]) {
                const DarkPatch& patch = s.patches[static_cast<std::size_t>(k)];
                if ((hit.q - patch.centre).norm() <= patch.radius)
                    stoneLevel = p.jointIntensity; // soiled: joint-coloured
            }
            if (hit.stoneShare >= 1.0 && stoneLevel != p.jointIntensity)
                pureStonePoints.push_back(global.size() - 1);
        } else {
            const auto near = stonesNear(s, hit.q, p.beamRadius);
            if (!near.empty())
                stoneLevel = p.stoneIntensity + s.stones[static_cast<std::size_t>(near.front())].tint;
        }
        const double level = hit.stoneShare * stoneLevel + (1.0 - hit.stoneShare) * p.jointIntensity;
        intensity.push_back(static_cast<float>(level - p.incidenceFalloff * (1.0 - hit.cosIncidence) +
                                               p.intensityNoise * gaussian(rng)));
        s.stoneId.push_back(hit.stone);
        s.part.push_back(hit.stone < 0 ? StonePart::Joint : hit.arris ? StonePart::Arris : StonePart::Face);
    });
    SplitMix64 rng(p.seed, 0xDA4C);
    for (int k = 0; k < p.darkPoints && !pureStonePoints.empty(); ++k) { // isolated joint-coloured returns on stones
        const std::size_t pick = rng.below(pureStonePoints.size());
        const std::size_t i = pureStonePoints[pick];
        pureStonePoints[pick] = pureStonePoints.back(), pureStonePoints.pop_back();
        intensity[i] = static_cast<float>(p.jointIntensity + p.intensityNoise * gaussian(rng));
        s.darkPointIndices.push_back(i);
    }
    s.cloud = makeCloud(global, "stone wall");
    s.cloud.addField("intensity").values() = std::move(intensity);
    s.cloud.sensors().push_back(sensorPose(s.frame, s.scanner));
    return s;
}

// ------------------------------------------------------------------ params

inline std::string describe(const StoneWallParams& p)
{
    return std::to_string(p.courses) + "x" + std::to_string(p.stonesPerCourse) + " stones " +
           format("%.0f-%.0f cm x %.0f cm, joint %.1f mm recess %.1f mm, spacing %.1f mm, noise %.1f mm, ",
                  p.stoneWidthMin * 100, p.stoneWidthMax * 100, p.courseHeight * 100, p.jointWidth * 1e3,
                  p.jointRecess * 1e3, p.spacing * 1e3, p.rangeNoise * 1e3) +
           format("stone %.0f joint %.0f sigma %.0f (contrast %.1f sigma), station %.1f m, heading %.0f deg, ",
                  p.stoneIntensity, p.jointIntensity, p.intensityNoise,
                  std::abs(p.stoneIntensity - p.jointIntensity) / p.intensityNoise, p.stationDistance, p.headingDeg) +
           std::to_string(p.darkPoints) + " dark points, " + std::to_string(p.darkPatches) + " patches" +
           (p.courseHeights.empty() ? "" : ", varying courses") + ", seed " + std::to_string(p.seed);
}

//! 320 stones, 12 mm joints recessed 8 mm, contrast 5 sigma, 5 mm spacing.
inline StoneWallParams issueCase() { return StoneWallParams{}; }

inline double rayCount(const StoneWallParams& p)
{
    const ScanGrid g = scanGridFor(p, makeWallFrame(p.corner, p.headingDeg, p.tiltDeg));
    return static_cast<double>(g.columns()) * static_cast<double>(g.rows());
}

//! A wall drawn over the ranges real surveys span; see the file comment.
inline StoneWallParams drawFamily(std::uint64_t seed, double scale)
{
    SplitMix64 rng(seed, 0x570E);
    StoneWallParams p;
    p.seed = seed;
    p.jointWidth = uniform(rng, 0.005, 0.025);
    p.jointRecess = rng.uniform() < 0.25 ? 0.0 : uniform(rng, 0.0, 0.015);
    p.spacing = logUniform(rng, 0.002, std::min(0.02, p.jointWidth));
    p.rangeNoise = logUniform(rng, 0.001, 0.005);
    p.beamRadius = std::min(uniform(rng, 0.001, 0.0025), 0.4 * p.jointWidth);
    p.intensityNoise = uniform(rng, 40.0, 200.0);
    const double contrast = uniform(rng, 3.0, 10.0) * p.intensityNoise;
    p.jointIntensity = uniform(rng, -1500.0, 1500.0 - contrast);
    p.stoneIntensity = p.jointIntensity + contrast;
    if (rng.uniform() < 0.5) // stones darker than joints (Boucher's cloud n°1)
        std::swap(p.jointIntensity, p.stoneIntensity);
    p.stoneTint = uniform(rng, 0.0, 0.3) * p.intensityNoise;
    p.incidenceFalloff = uniform(rng, 0.0, 0.6) * contrast;
    p.stoneWidthMin = uniform(rng, 0.2, 0.5);
    p.stoneWidthMax = std::min(0.8, p.stoneWidthMin + uniform(rng, 0.1, 0.3));
    p.bondMinOverlap = uniform(rng, 0.05, 0.1);
    p.courseHeight = uniform(rng, 0.15, 0.40);
    const bool varyingCourses = rng.uniform() < 0.5;
    p.bulgeMin = uniform(rng, 0.0005, 0.002);
    p.bulgeMax = p.bulgeMin + uniform(rng, 0.0005, 0.002);
    p.stationHeight = uniform(rng, 1.4, 1.9);
    p.wallBase = uniform(rng, 0.0, 3.0);
    p.stationAlongFraction = uniform(rng, 0.3, 0.7);
    p.headingDeg = uniform(rng, 0.0, 360.0);
    p.tiltDeg = rng.uniform() < 0.5 ? 0.0 : uniform(rng, -1.0, 1.0);
    p.corner = drawProjectedCorner(rng);
    const double distanceFactor = uniform(rng, 0.5, 1.2);
    const double darkRate = uniform(rng, 0.0, 0.15);
    const bool patches = rng.uniform() < 0.5;
    // counts: 4-20 courses x 6-25 stones at full size; a small scale caps them (4-6 x 6-9 at 0.05)
    const int maxCourses = std::clamp(static_cast<int>(std::lround(26.0 * std::sqrt(scale))), 4, 20);
    const int maxStones = std::clamp(static_cast<int>(std::lround(40.0 * std::sqrt(scale))), 6, 25);
    p.courses = 4 + static_cast<int>(rng.below(static_cast<std::uint64_t>(maxCourses - 3)));
    p.stonesPerCourse = 6 + static_cast<int>(rng.below(static_cast<std::uint64_t>(maxStones - 5)));
    std::vector<double> heights;
    for (int c = 0; c < p.courses; ++c)
        heights.push_back(std::clamp(p.courseHeight + uniform(rng, -0.06, 0.06), 0.15, 0.40));
    const double budget = std::max(2e5, 6e6 * scale);
    auto settle = [&] {
        p.courseHeights.clear();
        if (varyingCourses)
            p.courseHeights.assign(heights.begin(), heights.begin() + p.courses);
        p.stationDistance = std::max(3.0, distanceFactor * std::max(panelWidth(p), 1.5 * panelHeight(p)));
    };
    for (settle(); rayCount(p) > budget && (p.courses > 4 || p.stonesPerCourse > 6); settle()) {
        if (p.stonesPerCourse > 6 && (p.stonesPerCourse >= 2 * p.courses || p.courses <= 4))
            --p.stonesPerCourse;
        else
            --p.courses;
    }
    const double rays = rayCount(p);
    if (rays > budget)
        p.spacing = std::min({0.02, p.jointWidth, p.spacing * std::sqrt(rays / budget)});
    const int stones = p.courses * p.stonesPerCourse;
    p.darkPoints = static_cast<int>(std::lround(darkRate * stones));
    p.darkPatches = patches ? 1 + static_cast<int>(rng.below(static_cast<std::uint64_t>(stones / 10 + 1))) : 0;
    return p;
}

// ------------------------------------------------------------------ scoring

struct StoneMatch
{
    int polygon = -1;         //!< detected polygon with the best IoU
    double iou = 0.0;
    double hausdorff = kInf;  //!< symmetric boundary Hausdorff distance to that polygon (m)
    int polygonsAbove = 0;    //!< polygons with IoU >= rightIoU
    bool right = false;
};

struct StoneWallScore
{
    std::vector<StoneMatch> stones; //!< per true stone
    int detected = 0;
    int stonesRight = 0;
    int falsePolygons = 0;
    double fractionRight = 0.0, falseFraction = 0.0;
    double meanIoU = 0.0;
    bool meetsIssueTarget = false;
    std::string summary() const
    {
        return std::to_string(stonesRight) + "/" + std::to_string(stones.size()) + " stones right (" +
               format("%.2f %%), ", 100 * fractionRight) + std::to_string(falsePolygons) + "/" + std::to_string(detected) +
               format(" false polygons (%.2f %%), mean IoU %.4f", 100 * falseFraction, meanIoU);
    }
};

struct StoneScoreOptions
{
    double rightIoU = 0.8;
    double hausdorffTolerance = 0.03; //!< m
    double falseIoU = 0.5;
    double targetRight = 0.98, targetFalse = 0.02;
};

//! Scores one closed polygon per detected stone (3D, global coordinates).
inline StoneWallScore scorePolygons(const StoneWallScene& s, const std::vector<Ring3>& polygons,
                                    const StoneScoreOptions& opt = {})
{
    StoneWallScore out;
    std::vector<Polygon2> flat;
    std::vector<Box2> boxes;
    for (const auto& ring : polygons) {
        flat.push_back(projectRing(s.frame, ring));
        boxes.push_back(boxOf(flat.back()));
    }
    out.detected = static_cast<int>(polygons.size());
    std::vector<double> bestForPolygon(polygons.size(), 0.0);
    double iouSum = 0.0;
    for (std::size_t k = 0; k < s.stones.size(); ++k) {
        StoneMatch m;
        const Box2 tb = boxOf(s.stoneTruth[k]);
        for (std::size_t i = 0; i < flat.size(); ++i) {
            if (flat[i].size() < 3 || !boxes[i].overlaps(tb))
                continue;
            const double iou = polygonOverlap(flat[i], s.stoneTruth[k]).iou();
            bestForPolygon[i] = std::max(bestForPolygon[i], iou);
            m.polygonsAbove += iou >= opt.rightIoU;
            if (iou > m.iou)
                m.iou = iou, m.polygon = static_cast<int>(i);
        }
        if (m.polygon >= 0)
            m.hausdorff = boundaryHausdorff(flat[static_cast<std::size_t>(m.polygon)], s.stoneTruth[k]);
        m.right = m.polygonsAbove == 1 && m.hausdorff <= opt.hausdorffTolerance;
        out.stonesRight += m.right;
        iouSum += m.iou;
        out.stones.push_back(m);
    }
    for (double b : bestForPolygon)
        out.falsePolygons += b < opt.falseIoU;
    out.fractionRight = s.stones.empty() ? 1.0 : static_cast<double>(out.stonesRight) / s.stones.size();
    out.falseFraction = polygons.empty() ? 0.0 : static_cast<double>(out.falsePolygons) / polygons.size();
    out.meanIoU = s.stones.empty() ? 1.0 : iouSum / s.stones.size();
    out.meetsIssueTarget = out.fractionRight >= opt.targetRight && out.falseFraction <= opt.targetFalse;
    return out;
}

//! Point-level agreement of a tool's per-point labels (< 0: joint, else a
//! segment id of the tool's own numbering).
struct LabelScore
{
    //! Boucher's rates (%): stone detection, stone false alarms, joint detection, joint false alarms.
    double p1 = 0, p2 = 0, p3 = 0, p4 = 0;
    double onOwnStone = 0;                  //!< share of true stone points whose segment's majority stone is theirs
};

inline LabelScore scoreLabels(const StoneWallScene& s, const std::vector<int>& labels)
{
    LabelScore out;
    double tp = 0, fp = 0, fn = 0, tn = 0;
    std::map<int, std::map<int, std::size_t>> votes; // segment -> true stone -> count
    const std::size_t n = std::min(labels.size(), s.stoneId.size());
    for (std::size_t i = 0; i < n; ++i) {
        const bool isStone = s.stoneId[i] >= 0, saysStone = labels[i] >= 0;
        tp += isStone && saysStone, fp += !isStone && saysStone, fn += isStone && !saysStone, tn += !isStone && !saysStone;
        if (isStone && saysStone)
            ++votes[labels[i]][s.stoneId[i]];
    }
    std::map<int, int> majority;
    for (const auto& [segment, counts] : votes)
        majority[segment] = std::max_element(counts.begin(), counts.end(), [](const auto& a, const auto& b) {
                                return a.second < b.second;
                            })->first;
    std::size_t own = 0;
    for (std::size_t i = 0; i < n; ++i)
        own += s.stoneId[i] >= 0 && labels[i] >= 0 && majority[labels[i]] == s.stoneId[i];
    out.p1 = tp + fn > 0 ? 100 * tp / (tp + fn) : 0;
    out.p2 = tp + fp > 0 ? 100 * fp / (tp + fp) : 0;
    out.p3 = tn + fp > 0 ? 100 * tn / (tn + fp) : 0;
    out.p4 = tn + fn > 0 ? 100 * fn / (tn + fn) : 0;
    out.onOwnStone = tp + fn > 0 ? own / (tp + fn) : 0;
    return out;
}

//! The truth as polygons a perfect tool would return (3D, global).
inline std::vector<Ring3> truthPolygons(const StoneWallScene& s)
{
    std::vector<Ring3> out;
    for (const auto& rect : s.stoneTruth) {
        Ring3 r;
        for (const auto& q : rect)
            r.push_back(s.frame.toGlobal({q.x(), q.y(), 0.0}));
        out.push_back(r);
    }
    return out;
}

} // namespace scandiff::test::family::stonewall
