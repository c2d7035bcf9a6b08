// SPDX-License-Identifier: GPL-3.0-or-later
// Stone or joint per point from intensity and relief, with levels taken
// locally: the intensity of a wall falls with the incidence angle across it
// (thesis 003 §I: "intensity decreases as the incidence moves away from the
// normal"), so one global threshold leaves a far end's joints in the stone
// class; and a wall is rarely flat to the millimetre, so a joint's recess is
// measured from the faces around it, not from one plane.
#include "StoneEvidence.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/RobustStatistics.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace scandiff::plugins {

namespace {

//! Points grouped by square cells of the wall plane; a point's neighbourhood
//! is the 3 x 3 block of cells around its own.
struct CellGrid
{
    double size = 1.0;
    Eigen::Vector2d min = Eigen::Vector2d::Zero();
    int columns = 1, rows = 1;
    std::vector<std::uint32_t> cellOfPoint;
    std::vector<std::uint32_t> start;   //!< members of cell c: members[start[c] .. start[c + 1])
    std::vector<std::uint32_t> members;

    CellGrid(const std::vector<Eigen::Vector2d>& uv, double cellSize) : size(cellSize)
    {
        Eigen::Vector2d max = uv.front();
        min = uv.front();
        for (const Eigen::Vector2d& q : uv) {
            min = min.cwiseMin(q);
            max = max.cwiseMax(q);
        }
        // A wall of 100 m x 20 m at 5 cm cells is 800,000 cells; the caps only
        // guard against a window given far too small for the wall, or a
        // stray point far away stretching the box: at most 20,000 cells a
        // side and 4 million in all.
        const Eigen::Vector2d extent = max - min;
        size = std::max({size, std::max(extent.x(), extent.y()) / 20000.0, std::sqrt(extent.x() * extent.y() / 4.0e6)});
        if (!(size > 0) || !std::isfinite(size))
            size = 1.0; // every point at one place: one cell
        columns = static_cast<int>(extent.x() / size) + 1;
        rows = static_cast<int>(extent.y() / size) + 1;
        const std::size_t cells = static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows);
        cellOfPoint.resize(uv.size());
        start.assign(cells + 1, 0);
        for (std::size_t i = 0; i < uv.size(); ++i) {
            const int cx = std::min(columns - 1, static_cast<int>((uv[i].x() - min.x()) / size));
            const int cy = std::min(rows - 1, static_cast<int>((uv[i].y() - min.y()) / size));
            cellOfPoint[i] = static_cast<std::uint32_t>(cy * columns + cx);
            ++start[cellOfPoint[i] + 1];
        }
        for (std::size_t c = 0; c < cells; ++c)
            start[c + 1] += start[c];
        members.resize(uv.size());
        std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
        for (std::size_t i = 0; i < uv.size(); ++i)
            members[fill[cellOfPoint[i]]++] = static_cast<std::uint32_t>(i);
    }
    std::size_t cells() const { return start.size() - 1; }

    //! Calls visit(cell) for the cells of the 3 x 3 block around `cell`.
    template <typename Visit> void forBlock(std::size_t cell, Visit&& visit) const
    {
        const int cx = static_cast<int>(cell % static_cast<std::size_t>(columns)), cy = static_cast<int>(cell / static_cast<std::size_t>(columns));
        for (int y = std::max(0, cy - 1); y <= std::min(rows - 1, cy + 1); ++y)
            for (int x = std::max(0, cx - 1); x <= std::min(columns - 1, cx + 1); ++x)
                visit(static_cast<std::size_t>(y) * static_cast<std::size_t>(columns) + static_cast<std::size_t>(x));
    }
};

//! The two classes' intensity levels around each cell (means over its 3 x 3
//! block, drawn towards the wall's level by a few points' weight where a
//! class is nearly absent from the block).
struct LocalLevels
{
    std::vector<double> stone, joint;
    double stoneGlobal = 0.0, jointGlobal = 0.0;
};

LocalLevels localLevels(const CellGrid& grid, const std::vector<float>& intensity, const std::vector<std::uint8_t>& stone)
{
    const std::size_t cells = grid.cells();
    std::vector<double> sum[2] = {std::vector<double>(cells, 0.0), std::vector<double>(cells, 0.0)};
    std::vector<double> count[2] = {std::vector<double>(cells, 0.0), std::vector<double>(cells, 0.0)};
    double totalSum[2] = {0, 0}, totalCount[2] = {0, 0};
    for (std::size_t i = 0; i < intensity.size(); ++i)
        if (std::isfinite(intensity[i])) {
            const int k = stone[i];
            sum[k][grid.cellOfPoint[i]] += intensity[i];
            count[k][grid.cellOfPoint[i]] += 1.0;
            totalSum[k] += intensity[i];
            totalCount[k] += 1.0;
        }
    LocalLevels levels;
    levels.jointGlobal = totalSum[0] / std::max(1.0, totalCount[0]);
    levels.stoneGlobal = totalSum[1] / std::max(1.0, totalCount[1]);
    constexpr double kPriorPoints = 10.0;
    levels.stone.resize(cells);
    levels.joint.resize(cells);
    for (std::size_t c = 0; c < cells; ++c) {
        double s[2] = {0, 0}, n[2] = {0, 0};
        grid.forBlock(c, [&](std::size_t b) {
            for (int k = 0; k < 2; ++k)
                s[k] += sum[k][b], n[k] += count[k][b];
        });
        levels.joint[c] = (s[0] + kPriorPoints * levels.jointGlobal) / (n[0] + kPriorPoints);
        levels.stone[c] = (s[1] + kPriorPoints * levels.stoneGlobal) / (n[1] + kPriorPoints);
    }
    return levels;
}

//! The stone faces' height around each cell: the median height of the stone
//! points of its 3 x 3 block (of all its points when it holds no stone point).
std::vector<double> faceHeights(const CellGrid& grid, const std::vector<double>& height, const std::vector<std::uint8_t>& stone)
{
    std::vector<double> face(grid.cells(), 0.0), stoneHeights, allHeights;
    for (std::size_t c = 0; c < grid.cells(); ++c) {
        if (grid.start[c] == grid.start[c + 1])
            continue; // no point asks for it
        stoneHeights.clear();
        allHeights.clear();
        grid.forBlock(c, [&](std::size_t b) {
            for (std::uint32_t m = grid.start[b]; m < grid.start[b + 1]; ++m) {
                const std::uint32_t i = grid.members[m];
                (stone[i] ? stoneHeights : allHeights).push_back(height[i]);
            }
        });
        face[c] = medianInPlace(stoneHeights.empty() ? allHeights : stoneHeights);
    }
    return face;
}

//! How far apart two classes of a measure are, in the spread within them:
//! |difference of the medians| / the pooled robust standard deviation.
double separation(const std::vector<double>& values, const std::vector<std::uint8_t>& inClass, const std::vector<std::uint8_t>& valid)
{
    std::vector<double> parts[2];
    for (std::size_t i = 0; i < values.size(); ++i)
        if (valid[i])
            parts[inClass[i]].push_back(values[i]);
    if (parts[0].size() < 3 || parts[1].size() < 3)
        return 0.0;
    const double centre0 = medianInPlace(parts[0]), centre1 = medianInPlace(parts[1]);
    std::vector<double> deviations;
    for (int k = 0; k < 2; ++k)
        for (double v : parts[k])
            deviations.push_back(v - (k ? centre1 : centre0));
    const double sigma = robustSigma(deviations, 0.0);
    return sigma > 0 ? std::abs(centre1 - centre0) / sigma : 0.0;
}

//! The classes' start: the intensity's split, or the relief's when that
//! parts the points more clearly (a wall whose joints are recessed but of
//! the stones' own tone: pointed with lime, or dusty). The relief's split is
//! the inter-means threshold of the offsets from the faces around (the
//! median of all points, mostly faces); the side with more points is stone,
//! and it is a start only when the other side holds under a third of them.
void startFromTheReliefIfClearer(const CellGrid& grid, const std::vector<double>& height, const std::vector<float>& intensity,
                                 std::vector<std::uint8_t>& stone)
{
    const std::size_t n = height.size();
    std::vector<std::uint8_t> valid(n), everything(n, 1);
    for (std::size_t i = 0; i < n; ++i)
        valid[i] = std::isfinite(intensity[i]);
    const std::vector<double> face = faceHeights(grid, height, everything);
    std::vector<double> offset(n);
    std::vector<float> offsets;
    for (std::size_t i = 0; i < n; ++i) {
        offset[i] = height[i] - face[grid.cellOfPoint[i]];
        if (valid[i])
            offsets.push_back(static_cast<float>(offset[i]));
    }
    InterMeansThreshold split;
    try {
        split = interMeansThreshold(offsets);
    } catch (const Error&) {
        return; // every offset equal: no relief to start from
    }
    // Joints are narrow lines between stones: a minority. An even split is
    // the noise of a flush wall cut in two, not a relief.
    if (3 * std::min(split.highCount, split.lowCount) > std::max<std::size_t>(1, offsets.size()))
        return;
    const bool jointsAbove = split.highCount < split.lowCount;
    std::vector<std::uint8_t> byRelief(n, 0);
    for (std::size_t i = 0; i < n; ++i)
        byRelief[i] = valid[i] && ((offset[i] > split.threshold) != jointsAbove);
    std::vector<double> values(intensity.begin(), intensity.end());
    for (std::size_t i = 0; i < n; ++i)
        if (!valid[i])
            values[i] = 0.0;
    if (separation(offset, byRelief, valid) > separation(values, stone, valid))
        stone = std::move(byRelief);
}

//! Each class's mean intensity as classified (the threshold when a class is empty).
void classMeans(const std::vector<float>& intensity, StoneEvidence& out)
{
    double sums[2] = {0, 0};
    std::size_t counts[2] = {0, 0};
    for (std::size_t i = 0; i < intensity.size(); ++i)
        if (std::isfinite(intensity[i])) {
            sums[out.stone[i]] += intensity[i];
            ++counts[out.stone[i]];
        }
    out.jointMean = counts[0] ? sums[0] / static_cast<double>(counts[0]) : out.threshold;
    out.stoneMean = counts[1] ? sums[1] / static_cast<double>(counts[1]) : out.threshold;
}

} // namespace

StoneEvidence classifyStonePoints(const std::vector<Eigen::Vector2d>& uv, const std::vector<double>& height,
                                  const std::vector<float>& intensity, double spacing, const StoneEvidenceParams& params,
                                  ProgressTicker& ticker)
{
    const std::size_t n = uv.size();
    StoneEvidence out;
    bool oneIntensity = false; // a field of one value: only the relief can part the points
    if (params.threshold) {
        out.threshold = *params.threshold;
    } else {
        try {
            const InterMeansThreshold found = interMeansThreshold(intensity);
            out.threshold = found.threshold;
            out.thresholdIterations = found.iterations;
        } catch (const Error&) {
            if (!params.localLevels || !params.relief)
                throw;
            oneIntensity = true;
        }
    }
    out.polarity = params.polarity;
    if (out.polarity == StonePolarity::Auto) {
        std::size_t below = 0, above = 0;
        for (float v : intensity)
            if (std::isfinite(v))
                (v <= out.threshold ? below : above) += 1;
        out.polarity = below >= above ? StonePolarity::Dark : StonePolarity::Bright;
    }
    out.stone.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const float v = intensity[i];
        out.stone[i] = std::isfinite(v) && (oneIntensity || (out.polarity == StonePolarity::Dark ? v <= out.threshold : v > out.threshold));
    }
    out.recessed.assign(n, 0);
    if (!params.localLevels) {
        classMeans(intensity, out);
        return out; // the thesis's classification: the threshold alone, on the whole wall
    }

    const double window = params.window > 0 ? params.window : std::max(0.15, 30.0 * spacing);
    const CellGrid grid(uv, window / 3.0);
    if (params.relief)
        startFromTheReliefIfClearer(grid, height, intensity, out.stone);
    std::vector<double> offset(n, 0.0);
    std::vector<double> residuals, stoneOffsets, jointOffsets;
    constexpr int kRounds = 8;
    for (out.iterations = 1; out.iterations <= kRounds; ++out.iterations) {
        ticker.checkCancel();
        const LocalLevels levels = localLevels(grid, intensity, out.stone);
        std::size_t stones = 0, joints = 0;
        residuals.clear();
        for (std::size_t i = 0; i < n; ++i)
            if (std::isfinite(intensity[i])) {
                const std::uint32_t c = grid.cellOfPoint[i];
                residuals.push_back(intensity[i] - (out.stone[i] ? levels.stone[c] : levels.joint[c]));
                (out.stone[i] ? stones : joints) += 1;
            }
        if (stones == 0 || joints == 0)
            throw Error(ErrorCode::InvalidData, "stones: every point falls in one class; give a threshold between the stones' and "
                                                "the joints' intensities");
        const double intensitySigma = std::max(robustSigma(residuals, 0.0), 1e-9 * (1.0 + std::abs(levels.stoneGlobal)));

        // The offset from the stone faces around, and whether the joints stand apart by it.
        const std::vector<double> face = faceHeights(grid, height, out.stone);
        stoneOffsets.clear();
        jointOffsets.clear();
        for (std::size_t i = 0; i < n; ++i) {
            offset[i] = height[i] - face[grid.cellOfPoint[i]];
            if (std::isfinite(intensity[i]))
                (out.stone[i] ? stoneOffsets : jointOffsets).push_back(offset[i]);
        }
        const double stoneLevel = medianInPlace(stoneOffsets), jointLevel = medianInPlace(jointOffsets);
        out.reliefNoise = std::max(robustSigma(stoneOffsets, stoneLevel), 1e-9);
        out.jointOffset = jointLevel - stoneLevel;
        out.faceOffset = stoneLevel;
        out.reliefUsed = params.relief && std::abs(out.jointOffset) >= 0.5 * out.reliefNoise;

        // Linear discriminant of two classes of equal spread per measure (no
        // quadratic term, so an outlier in one measure cannot swamp the other),
        // each measure's vote bounded, plus the classes' prior odds.
        constexpr double kVoteBound = 12.0;
        const double prior = std::log(static_cast<double>(stones) / static_cast<double>(joints));
        const double reliefWeight = -out.jointOffset / (out.reliefNoise * out.reliefNoise);
        const double reliefMiddle = 0.5 * (stoneLevel + jointLevel);
        std::size_t changed = 0;
        for (std::size_t i = 0; i < n; ++i) {
            std::uint8_t isStone = 0;
            if (std::isfinite(intensity[i])) {
                const std::uint32_t c = grid.cellOfPoint[i];
                const double contrast = levels.stone[c] - levels.joint[c];
                double vote = std::clamp(contrast / (intensitySigma * intensitySigma) * (intensity[i] - 0.5 * (levels.stone[c] + levels.joint[c])),
                                         -kVoteBound, kVoteBound);
                if (out.reliefUsed)
                    vote += std::clamp(reliefWeight * (offset[i] - reliefMiddle), -kVoteBound, kVoteBound);
                isStone = vote + prior > 0.0;
            }
            changed += isStone != out.stone[i];
            out.stone[i] = isStone;
        }
        out.intensitySeparation = (levels.stoneGlobal - levels.jointGlobal) / intensitySigma;
        ticker.step(n / kRounds);
        if (changed * 2000 < n)
            break; // fewer than one point in 2,000 moved: the classes have settled
    }
    out.iterations = std::min(out.iterations, kRounds);
    classMeans(intensity, out);
    if (out.reliefUsed) {
        const double direction = out.jointOffset > 0 ? 1.0 : -1.0;
        const double cut = std::max(0.5 * std::abs(out.jointOffset), 2.5 * out.reliefNoise);
        for (std::size_t i = 0; i < n; ++i)
            out.recessed[i] = direction * (offset[i] - out.faceOffset) > cut;
    }
    return out;
}

} // namespace scandiff::plugins
