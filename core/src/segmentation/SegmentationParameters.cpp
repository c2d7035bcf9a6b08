// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/segmentation/Classification.h>
#include <scandiff/core/segmentation/ConnectedComponents.h>
#include <scandiff/core/segmentation/FastMarching.h>
#include <scandiff/core/segmentation/SegmentationParameters.h>

#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>

namespace scandiff {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

//! "A,B" or "A;B" (the CLI joins repeated values with ';').
std::vector<double> numbers(const std::string& text, const std::string& what)
{
    std::string commas = text;
    for (char& c : commas)
        if (c == ';')
            c = ',';
    return parseNumberList(commas, what);
}

} // namespace

const std::vector<ParameterSpec>& segmentationParameters()
{
    static const std::vector<ParameterSpec> parameters = [] {
        const LocalChiSquareParams chi;
        const ConnectedComponentsParams cc;
        const PropagationParams propagation;
        return std::vector<ParameterSpec>{
            ParameterSpec::text("field", "Field", "Scalar field to segment (the distances)", "c2c_distance").asFieldOf("input"),
            ParameterSpec::boolean("absolute", "Absolute values", "Segment |value| (signed distances as unsigned ones)", false),
            ParameterSpec::real("above", "Above", "Changed: values >= this threshold (§3.2.1)", 0.1, -1e30, 1e30)
                .asAlternative("method")
                .onlyWith("!propagate"),
            ParameterSpec::text("range", "Range", "Changed: values in [A, B], given as 'A B' or 'A,B' (§3.2.1)")
                .takingValues(2)
                .asAlternative("method")
                .onlyWith("!propagate"),
            ParameterSpec::integer("kmeans", "K-means classes",
                                   "Changed: K-means with this many classes, all but the one nearest 0 (§3.2.2)", 2, 2, 64)
                .asAlternative("method")
                .onlyWith("!propagate"),
            ParameterSpec::choice("stat-test", "Local statistical test",
                                  "Changed: the local chi-square test against this noise model (§3.2.3)", {"gaussian", "weibull"},
                                  "weibull")
                .asAlternative("method")
                .onlyWith("!propagate"),
            ParameterSpec::integer("neighbours", "Test neighbours", "stat-test: n nearest neighbours per test (sqrt(n) classes)",
                                   chi.neighbours, 4, 1024, "points")
                .onlyWith("stat-test"),
            ParameterSpec::real("confidence", "Confidence", "stat-test: confidence of the test (the chi-square quantile)",
                                chi.confidence, 0.5, 0.999999)
                .onlyWith("stat-test"),
            ParameterSpec::choice("calibration", "Null distribution",
                                  "stat-test: spatial: the cut is the quantile scaled by how much more the chi-square distances of "
                                  "this field spread than independent draws would (neighbouring distances are correlated; fitted on "
                                  "the data); tabulated: the textbook quantile (thesis 000 eq. 3.2)",
                                  {"spatial", "tabulated"}, nullCalibrationName(chi.calibration))
                .onlyWith("stat-test"),
            ParameterSpec::real("chi2-threshold", "Chi-square cut", "stat-test: cut on the chi-square distance instead of the quantile",
                                20.0, 0.0, 1e12)
                .asOptional()
                .onlyWith("stat-test"),
            ParameterSpec::text("fit-box", "Unchanged zone",
                                "stat-test: fit the noise on the points inside X0,Y0,Z0,X1,Y1,Z1 (global coordinates) instead of "
                                "the whole field")
                .asOptional()
                .onlyWith("stat-test"),
            ParameterSpec::text("noise", "Noise parameters",
                                "stat-test: known noise parameters instead of a fit: MEAN,SIGMA (gaussian) or SHAPE,SCALE (weibull)")
                .asOptional()
                .onlyWith("stat-test"),
            ParameterSpec::boolean("components", "Connected components",
                                   "Group the changed points by connected components on the octree grid (§3.2.4); without it "
                                   "all changed points form region 1",
                                   false),
            ParameterSpec::integer("level", "Octree level",
                                   "Grid of the components / propagation: octree level 1..21 of the cloud's cube; 0 = automatic",
                                   cc.level, 0, 21)
                .withZeroMeaning("automatic"),
            ParameterSpec::choice("connectivity", "Connectivity", "Adjacent cells: faces (6), + edges (18), + corners (26)",
                                  {"6", "18", "26"}, "26")
                .onlyWith("components"),
            // Used by every mode (components, propagation, the single region): always shown.
            // 10 as CloudCompare's connected components: a test at 99 % flags
            // about 1 % of the unchanged points, scattered in specks of a few
            // points that are no change anyone can act on.
            ParameterSpec::integer("min-points", "Minimum region size", "Smaller regions are dropped", kDefaultMinRegionPoints, 1,
                                   1000000000, "points"),
            ParameterSpec::boolean("propagate", "Front propagation",
                                   "Segment by gradient-constrained fast marching (§3.3) instead of a classification", false),
            ParameterSpec::real("alpha", "Alpha", "propagate: speed exp(alpha (|grad|_j - |grad|_i)) (eq. 3.11)", propagation.alpha,
                                0.0, 1e4)
                .onlyWith("propagate"),
            ParameterSpec::real("min-seed", "Minimum seed value", "propagate: regions start only from values >= this", 0.1, -1e30,
                                1e30)
                .asOptional()
                .onlyWith("propagate"),
            ParameterSpec::boolean("keep-background", "Keep background regions",
                                   "propagate: also keep the regions whose values are the field's noise (a noise value above "
                                   "the seed value started them); left out by default",
                                   false)
                .onlyWith("propagate"),
            ParameterSpec::real("stop-speed", "Stop speed", "propagate: the front does not cross where the speed falls below this",
                                propagation.stopSpeed, 1e-12, 1.0)
                .onlyWith("propagate"),
            ParameterSpec::real("gradient-radius", "Gradient radius", "propagate: neighbourhood radius of the gradient; 0 = automatic",
                                0.0, 0.0, 1e9, "m")
                .onlyWith("propagate")
                .withZeroMeaning("automatic"),
            ParameterSpec::real("smoothing", "Gradient smoothing", "propagate: Gaussian smoothing of the gradient norm, sigma", 0.05,
                                1e-9, 1e9, "m")
                .asOptional()
                .onlyWith("propagate"),
            ParameterSpec::text("report-field", "Report field",
                                "The distances the region report gives (mean, max, RMS) when they are not the segmented field: "
                                "segment on m3c2_significant, report m3c2_distance")
                .asOptional()
                .asFieldOf("input"),
            ParameterSpec::text("uncertainty-field", "Uncertainty field",
                                "Each point's level of detection of the reported distances: gives each region's volume along "
                                "the distances with its uncertainty (default: m3c2_uncertainty when reporting m3c2_distance)")
                .asOptional()
                .asFieldOf("input"),
            ParameterSpec::real("outline-cell", "Outline cell",
                                "Cell of the regions' concave outlines; 0 = automatic (1.5 x the 4th-neighbour spacing)", 0.0, 0.0, 1e9,
                                "m")
                .withZeroMeaning("automatic"),
            ParameterSpec::choice("region-epoch", "Regions are in",
                                  "Volume: which epoch the segmented cloud is (later: the compared cloud, where appeared matter shows; "
                                  "earlier: the reference of a both-ways C2C, where removed matter shows); the volume is later minus earlier",
                                  {"later", "earlier"}, "later"),
            ParameterSpec::choice("column-height", "Column height",
                                  "Volume: each epoch's height in a grid column: its highest point (the surface seen from above), mean or lowest",
                                  {"highest", "mean", "lowest"}, "highest"),
            ParameterSpec::real("volume-cell", "Volume cell", "Volume: horizontal grid cell; 0 = the outline cell", 0.0, 0.0, 1e9, "m")
                .withZeroMeaning("the outline cell"),
        };
    }();
    return parameters;
}

namespace {

//! One classification method, or propagation alone.
void checkMethods(const ParameterValues& values)
{
    int methods = 0;
    for (const char* m : {"range", "above", "kmeans", "stat-test"})
        methods += values.has(m);
    const bool propagate = values.boolean("propagate");
    if (propagate && methods > 0)
        throw Error(ErrorCode::InvalidArgument, "segment: propagate replaces the classification; drop range/above/kmeans/stat-test");
    if (!propagate && methods != 1)
        throw Error(ErrorCode::InvalidArgument, methods == 0 ? "segment: choose a method: range, above, kmeans, stat-test or propagate"
                                                             : "segment: choose only one of range, above, kmeans and stat-test");
}

//! Regions grown from seeds by fast marching (thesis 000 §3.3): its fields
//! and summary, nothing classified first.
void propagate(const PointCloud& source, const std::string& fieldName, const ParameterValues& values, SegmentationRun& run,
               std::ostringstream& summary, ProgressObserver* progress)
{
    PropagationParams p;
    if (!values.has("min-seed"))
        throw Error(ErrorCode::InvalidArgument, "segment: propagate needs min-seed (the smallest value a region may start from)");
    p.minSeedValue = values.real("min-seed");
    p.alpha = values.real("alpha");
    p.stopSpeed = values.real("stop-speed");
    p.level = static_cast<int>(values.integer("level"));
    p.minPoints = static_cast<std::size_t>(values.integer("min-points"));
    p.keepBackground = values.boolean("keep-background");
    p.gradient.radius = values.real("gradient-radius");
    if (values.has("smoothing"))
        p.gradient.smoothingSigma = values.real("smoothing");
    PropagationResult r = propagationSegmentation(source, fieldName, p, progress);
    run.regionCount = r.regionCount;
    run.regionSizes = r.regionSizes;
    run.level = r.level;
    summary << "propagation (alpha " << p.alpha << ", stop speed " << p.stopSpeed << ", min seed " << p.minSeedValue << ", level "
            << r.level << "): " << r.regionCount << " regions";
    if (r.droppedRegions)
        summary << " (" << r.droppedRegions << " smaller than " << p.minPoints << " points dropped)";
    if (r.backgroundRegions)
        summary << "; " << r.backgroundRegions << (r.backgroundRegions == 1 ? " region" : " regions") << " of "
                << r.backgroundPoints << " points whose values are the field's noise (median below the seed value and "
                << r.noiseCeiling << ", the field's median + 3 sigma): background, "
                << (p.keepBackground ? "kept as asked" : "left out (keep-background keeps it)");
    run.fields.push_back(std::move(r.regionId));
    run.fields.push_back(std::move(r.arrivalTime));
    run.fields.push_back(std::move(r.gradient));
}

//! The changed points by a range or a lower bound.
ScalarField classifyByThresholds(const ScalarField& field, const ParameterValues& values, std::ostringstream& summary)
{
    double low = 0.0, high = kInf;
    if (values.has("range")) {
        const std::vector<double> range = parseNumberWords(values.text("range"), "range");
        if (range.size() != 2)
            throw Error(ErrorCode::InvalidArgument, "range: expected two values A B");
        low = range[0];
        high = range[1];
        summary << "range [" << low << ", " << high << "]";
    } else {
        low = values.real("above");
        summary << "above " << low;
    }
    return classifyByRange(field, low, high);
}

//! The changed points by K-means on the values (thesis 000 §3.2.2).
ScalarField classifyByKMeans(const ScalarField& field, const ParameterValues& values, SegmentationRun& run, std::ostringstream& summary,
                             ProgressObserver* progress)
{
    KMeansParams p;
    p.classes = static_cast<int>(values.integer("kmeans"));
    KMeansResult r = kMeans(field, p, progress);
    run.centres = r.centres;
    summary << "K-means (" << p.classes << " classes, centres";
    for (double c : r.centres)
        summary << ' ' << c;
    summary << ", " << r.iterations << " iterations)";
    run.fields.push_back(std::move(r.classes));
    return std::move(r.changed);
}

//! The noise of the local test when given: its two parameters, or a fit on
//! the values inside a box of points known unchanged. None: fitted on the field.
std::optional<NoiseDistribution> noiseFrom(const ParameterValues& values, NoiseModel model, const PointCloud& source,
                                           const ScalarField& field)
{
    if (values.has("noise")) {
        const std::vector<double> n = numbers(values.text("noise"), "noise");
        if (n.size() != 2 || !(n[1] > 0) || (model == NoiseModel::Weibull && !(n[0] > 0)))
            throw Error(ErrorCode::InvalidArgument,
                        "noise: expected MEAN,SIGMA (gaussian) or SHAPE,SCALE (weibull), the spread and shape positive");
        NoiseDistribution d;
        d.model = model;
        if (model == NoiseModel::Gaussian) {
            d.mean = n[0];
            d.sigma = n[1];
        } else {
            d.shape = n[0];
            d.scale = n[1];
        }
        return d;
    }
    if (!values.has("fit-box"))
        return std::nullopt;
    const std::vector<double> b = numbers(values.text("fit-box"), "fit-box");
    if (b.size() != 6)
        throw Error(ErrorCode::InvalidArgument, "fit-box: expected X0,Y0,Z0,X1,Y1,Z1");
    const Eigen::Vector3d lo(std::min(b[0], b[3]), std::min(b[1], b[4]), std::min(b[2], b[5]));
    const Eigen::Vector3d hi(std::max(b[0], b[3]), std::max(b[1], b[4]), std::max(b[2], b[5]));
    std::vector<std::size_t> inside;
    for (std::size_t i = 0; i < source.size(); ++i) {
        const Eigen::Vector3d g = source.globalPosition(i);
        if ((g.array() >= lo.array()).all() && (g.array() <= hi.array()).all() && field.hasValue(i))
            inside.push_back(i);
    }
    if (inside.size() < 2)
        throw Error(ErrorCode::InvalidArgument, "fit-box: fewer than 2 points with a value inside the box");
    return fitNoise(field, model, &inside);
}

//! The changed points by the local chi-square test (thesis 000 §3.2.3).
ScalarField classifyByChiSquare(const PointCloud& source, const std::string& fieldName, const ParameterValues& values,
                                SegmentationRun& run, std::ostringstream& summary, ProgressObserver* progress)
{
    LocalChiSquareParams p;
    p.model = parseNoiseModel(values.text("stat-test"));
    p.neighbours = static_cast<int>(values.integer("neighbours"));
    p.confidence = values.real("confidence");
    p.calibration = parseNullCalibration(values.text("calibration"));
    if (values.has("chi2-threshold"))
        p.threshold = values.real("chi2-threshold");
    p.noise = noiseFrom(values, p.model, source, *source.field(fieldName));
    LocalChiSquareResult r = localChiSquareTest(source, fieldName, p, progress);
    run.noise = r.noise;
    run.threshold = r.threshold;
    summary << "local chi-square test (" << noiseModelName(p.model) << ' ';
    if (p.model == NoiseModel::Gaussian)
        summary << "mean " << r.noise.mean << " sigma " << r.noise.sigma;
    else
        summary << "shape " << r.noise.shape << " scale " << r.noise.scale;
    if (r.fitRejected > 0)
        summary << ", fitted without " << r.fitRejected << " values beyond the noise";
    summary << ", n " << p.neighbours << ", " << r.classes << " classes, cut " << r.threshold;
    if (!p.threshold && p.calibration == NullCalibration::Spatial)
        summary << " (spatial calibration on " << r.nullScalePoints << " quiet points: " << r.nullScale << " x the tabulated "
                << r.quantileThreshold << ", their own quantile " << r.empiricalThreshold << ")";
    summary << ")";
    run.fields.push_back(std::move(r.chiSquare));
    return std::move(r.changed);
}

//! The changed points grouped into regions: connected components of the
//! octree's cells (thesis 000 §3.3), or all of them as one region.
ScalarField regionsOf(const PointCloud& source, const std::vector<std::uint8_t>& selected, const ParameterValues& values,
                      SegmentationRun& run, std::ostringstream& summary, ProgressObserver* progress)
{
    ScalarField regionId(fields::kRegionId, source.size());
    if (values.boolean("components")) {
        ConnectedComponentsParams p;
        p.level = static_cast<int>(values.integer("level"));
        p.connectivity = parseConnectivity(std::stoi(values.text("connectivity")));
        p.minPoints = static_cast<std::size_t>(values.integer("min-points"));
        ConnectedComponentsResult r = connectedComponents(source, selected, p, progress);
        run.regionCount = r.regionCount;
        run.regionSizes = r.regionSizes;
        run.level = r.level;
        summary << ", " << r.regionCount << " regions (level " << r.level << ", cell " << r.cellSize << " m, "
                << static_cast<int>(p.connectivity) << "-connectivity";
        if (r.droppedComponents)
            summary << ", " << r.droppedComponents << " components smaller than " << p.minPoints << " points dropped";
        summary << ")";
        return std::move(r.regionId);
    }
    if (run.changedCount >= static_cast<std::size_t>(values.integer("min-points"))) {
        for (std::size_t i = 0; i < selected.size(); ++i)
            if (selected[i])
                regionId.values()[i] = 1.0f;
        run.regionCount = 1;
        run.regionSizes = {run.changedCount};
        summary << ", one region";
    }
    return regionId;
}

} // namespace

SegmentationRun runSegmentation(const PointCloud& cloud, const ParameterValues& values, ProgressObserver* progress)
{
    const std::string fieldName = values.text("field");
    const ScalarField* original = cloud.field(fieldName);
    if (!original)
        throw Error(ErrorCode::InvalidArgument, "segment: cloud '" + cloud.name + "' has no field '" + fieldName + "'");
    if (cloud.empty())
        throw Error(ErrorCode::InvalidData, "segment: cloud '" + cloud.name + "' is empty");
    checkMethods(values);

    // The field segmented: the original, or its absolute values, under the
    // original name so the algorithms can find it on a working cloud.
    PointCloud working;
    const PointCloud* source = &cloud;
    if (values.boolean("absolute")) {
        // Positions are needed for neighbourhoods; only the one field is copied.
        working.setOrigin(cloud.origin());
        working.positions() = cloud.positions();
        working.name = cloud.name;
        working.addField(absoluteValues(*original));
        source = &working;
    }
    const ScalarField& field = *source->field(fieldName);

    SegmentationRun run;
    std::ostringstream summary;
    summary << std::setprecision(6);
    if (values.boolean("propagate")) {
        propagate(*source, fieldName, values, run, summary, progress);
        run.summary = summary.str();
        return run;
    }
    // Classify the points as changed or not, then group the changed ones.
    ScalarField changed = values.has("range") || values.has("above") ? classifyByThresholds(field, values, summary)
                          : values.has("kmeans")                     ? classifyByKMeans(field, values, run, summary, progress)
                                                                     : classifyByChiSquare(*source, fieldName, values, run, summary, progress);
    const std::vector<std::uint8_t> selected = selectionFromLabels(changed);
    for (std::uint8_t s : selected)
        run.changedCount += s;
    summary << ": " << run.changedCount << " changed points";
    ScalarField regionId = regionsOf(*source, selected, values, run, summary, progress);
    run.fields.push_back(std::move(changed));
    run.fields.push_back(std::move(regionId));
    run.summary = summary.str();
    return run;
}

void attachFields(PointCloud& cloud, SegmentationRun&& run)
{
    for (ScalarField& f : run.fields)
        cloud.addField(std::move(f));
    run.fields.clear();
}

RegionReportParams regionReportSettings(const ParameterValues& values, const PointCloud* reference)
{
    RegionReportParams p;
    p.distanceField = values.has("report-field") ? values.text("report-field") : values.text("field");
    if (values.has("uncertainty-field"))
        p.uncertaintyField = values.text("uncertainty-field");
    p.outlineCellSize = values.real("outline-cell");
    p.volumeCellSize = values.real("volume-cell");
    p.regionInLaterEpoch = values.text("region-epoch") == "later";
    const std::string height = values.text("column-height");
    p.columnHeight = height == "mean"     ? RegionReportParams::ColumnHeight::Mean
                     : height == "lowest" ? RegionReportParams::ColumnHeight::Lowest
                                          : RegionReportParams::ColumnHeight::Highest;
    p.reference = reference;
    return p;
}

} // namespace scandiff
