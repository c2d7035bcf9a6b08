// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Stone-by-stone drawing of a wall from its scan (thesis 003, Boucher 2015):
//! the points are classified into stone and joint by their intensity and their
//! relief (the joints' recess), isolated stone points removed, stone points
//! bridging a joint set aside, and each group of stone points separated by
//! joints becomes one closed polygon in the wall's best-fit plane.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/plugins/contours/PlanarContours.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace scandiff::plugins {

//! The iterative inter-means threshold of thesis 003 §II.1.3.2 (Ridler and
//! Calvard's isodata, on a global histogram, not Otsu): S = (mean of the values
//! <= S + mean of the values > S) / 2, repeated from S = the mean until the two
//! classes no longer change. Computed on the values themselves, not on bins.
struct InterMeansThreshold
{
    double threshold = 0.0;
    double lowMean = 0.0, highMean = 0.0;
    std::size_t lowCount = 0, highCount = 0;
    int iterations = 0;
};
//! Non-finite values are ignored. Throws Error(InvalidData) when fewer than
//! two distinct finite values remain (no threshold separates anything).
InterMeansThreshold interMeansThreshold(const std::vector<float>& values, std::optional<double> initial = std::nullopt);

//! Stones below or above the threshold; Auto: the class with more points
//! (stones cover most of a wall, joints are narrow lines between them).
enum class StonePolarity { Dark, Bright, Auto };
enum class StoneMethod { Classify, Grow };
StonePolarity parseStonePolarity(const std::string& name); //!< "dark", "bright", "auto"
StoneMethod parseStoneMethod(const std::string& name);     //!< "classify", "grow"

struct StoneParams
{
    std::string field = "intensity";
    StonePolarity polarity = StonePolarity::Auto;
    std::optional<double> threshold; //!< absent: the inter-means threshold
    //! true: the classes' intensity levels and the stone faces' surface taken
    //! over a window around each point, the points classified again until the
    //! classes settle (the threshold is the start); false: the threshold alone
    //! on the whole wall, as the thesis.
    bool localLevels = true;
    //! With local levels: each point's offset from the stone faces around it
    //! votes too (joints are usually recessed), when the joints stand apart
    //! from the faces by at least half the faces' noise.
    bool relief = true;
    double window = 0.0; //!< side of the local window (m); 0: max(0.15 m, 30 point spacings)
    StoneMethod method = StoneMethod::Classify;
    //! Cleaning: a stone point with fewer than `cleaningNeighbours` other stone
    //! points within `cleaningRadius` (0: 2 x the point spacing) is a joint
    //! point (thesis 003 §III.1.2.1.1: "isolated points").
    double cleaningRadius = 0.0;
    int cleaningNeighbours = 3;
    //! Largest circumradius of a stone's triangles (alpha-shape radius, thesis
    //! 003 §III.1.1); 0: a triangle is kept while its longest edge is within
    //! the knee of those edges measured in the spacing where each lies (the
    //! density of a scan falls across a wall seen obliquely: one radius for
    //! the whole wall riddles its far end with holes).
    double alpha = 0.0;
    //! Smallest stone polygon (m²); 0: 25 x the squared point spacing, or a
    //! twentieth of the median stone's area when that is larger.
    double minStoneArea = 0.0;
    //! Grow: neighbourhood radius R (0: 2 x the point spacing, thesis 003
    //! §II.2.1) and intensity variance tolerance tau (0: the variance of the
    //! stone class found by the threshold).
    double growRadius = 0.0;
    double growVariance = 0.0;
    //! Each stone's outline vectorised as the façade openings are (straight
    //! pieces and arcs, corners at their intersections, the edges moved half
    //! a spacing out where the joint begins): the alpha shape's boundary
    //! zigzags by a spacing and rounds every corner, 3 cm and more off the
    //! stone's edge at its corners. Off: the ring of the stone's triangles.
    bool vectorise = true;
};

struct Stone
{
    std::vector<Eigen::Vector3d> outline; //!< closed, counter-clockwise seen from the front, in the wall plane, global
    //! (vectorised: the corners; arcs as points every 2 degrees)
    Ring2d outline2d;                     //!< the same in the plane's (u, v)
    double area = 0.0, perimeter = 0.0;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero(); //!< of the polygon, global
    double planeRms = 0.0; //!< of the stone's points' distances to the wall plane
    std::size_t points = 0;
};

struct StoneWallResult
{
    PlaneFrame wall;
    double threshold = 0.0;
    int thresholdIterations = 0; //!< 0 when the threshold was given
    StonePolarity polarity = StonePolarity::Dark; //!< the one used (Auto resolved)
    double stoneMean = 0.0, jointMean = 0.0; //!< the two classes' mean intensities (the histogram's modes)
    double spacing = 0.0;        //!< median distance of a point to its nearest neighbour
    double alpha = 0.0;          //!< the outline's threshold: the alpha radius given, or the longest edge at the median spacing
    double jointOffset = 0.0;    //!< the joints' median offset from the stone faces (m, along the wall's normal; local levels only)
    double reliefNoise = 0.0;    //!< robust standard deviation of the stone points' offsets from their faces (m)
    bool reliefUsed = false;
    int classificationRounds = 0; //!< rounds of the local classification (0: the threshold alone)
    std::size_t pointsNearJoints = 0; //!< stone points near a joint, given to the nearest stone's core
    std::vector<std::int32_t> stoneOfPoint; //!< -1: joint, isolated, or in a dropped contour
    std::vector<std::uint8_t> stoneClass;   //!< 1: classified stone (before cleaning), 0: joint or no intensity
    std::vector<std::uint8_t> partingPoint; //!< 1: joint class or set back from the faces
    std::vector<std::uint8_t> jointLine;    //!< 1: on a joint, as the parting points line up (gaps in them included)
    std::size_t isolatedRemoved = 0, smallDropped = 0, nestedDropped = 0;
    std::vector<Stone> stones; //!< in order of their centroid: rows from the top, left to right
};

//! Throws Error(InvalidArgument) when the field is missing or a parameter is
//! invalid, Error(InvalidData) for fewer than 3 points or a wall that is not a
//! surface, Error(Cancelled) when the observer asks.
StoneWallResult extractStones(const PointCloud& cloud, const StoneParams& params, ProgressObserver* progress = nullptr);

} // namespace scandiff::plugins
