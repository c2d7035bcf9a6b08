// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Comparing a vector model with a reference (thesis 001 §5.6, Tab. 5.5; the
//! stone-level rates of thesis 003, with an objective matching rule).

#include <scandiff/plugins/contours/PlanarContours.h>

#include <vector>

namespace scandiff::plugins {

struct Polygon2d
{
    Ring2d outer;              //!< either orientation; may touch itself at vertices
    std::vector<Ring2d> holes; //!< either orientation
};

//! Area of the intersection of two polygons with holes, exactly (CGAL's
//! Boolean operations on an exact kernel). A ring touching itself at a vertex
//! counts as its simple loops; a ring that crosses itself is an Error(InvalidData).
double intersectionArea(const Polygon2d& a, const Polygon2d& b);
double polygonArea(const Polygon2d& p); //!< outer minus holes

//! Whether a ring is not a simple polygon (CGAL's exact predicates): two
//! edges that are not neighbours meet (cross, touch or overlap), or two
//! neighbours fold back onto each other, or a vertex repeats; what a CAD
//! program draws as a bow-tie. Fewer than 3 vertices: false.
bool crossesItself(const Ring2d& ring);

//! Thesis 001 Tab. 5.5 for a model A and a reference R. The thesis's prose
//! and formulas disagree on two of them; its tables follow the formulas,
//! which are kept here: branching = |R \ A| / |R ∩ A|, miss = |A \ R| / |R ∩ A|,
//! failure = |A \ R| / |R|. `excess` and `deficit` name the parts plainly.
struct AreaMeasures
{
    double reference = 0, model = 0, intersection = 0;
    double detection = 0; //!< ρd = |R ∩ A| / |R|
    double quality = 0;   //!< ρq = |R ∩ A| / |R ∪ A|
    double branching = 0; //!< ρb (as printed)
    double miss = 0;      //!< ρm (as printed)
    double failure = 0;   //!< ρf (as printed)
    double excess = 0;    //!< |A \ R|, the model's area outside the reference
    double deficit = 0;   //!< |R \ A|, the reference's area the model misses
};
AreaMeasures compareAreas(const Polygon2d& model, const Polygon2d& reference);

//! The symmetric Hausdorff distance between the boundaries (outer rings) of
//! two polygons, each boundary sampled every `step` (and at its vertices)
//! against the other's exact segments.
double boundaryHausdorff(const Ring2d& a, const Ring2d& b, double step = 0.001);

//! One model polygon matched to the references: "correct" when its IoU with
//! exactly one reference is at least `minIou` and no other reference overlaps
//! it by more than 10 % of that reference (thesis 003 §7.2 proposal).
struct PolygonMatching
{
    std::vector<int> referenceOfModel; //!< -1: incorrect (a false or merged contour)
    std::vector<double> iouOfModel;    //!< with its best reference
    std::size_t correct = 0;           //!< references with a correct model polygon
    double detectionRate = 0;          //!< P5 = correct / references
    double falseRate = 0;              //!< P6 = incorrect model polygons / model polygons
};
PolygonMatching matchPolygons(const std::vector<Polygon2d>& model, const std::vector<Polygon2d>& reference, double minIou = 0.8);

} // namespace scandiff::plugins
