// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/Classification.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace scandiff {

ScalarField classifyByRange(const ScalarField& field, double low, double high)
{
    if (std::isnan(low) || std::isnan(high) || low > high)
        throw Error(ErrorCode::InvalidArgument, "threshold: the range [" + std::to_string(low) + ", " + std::to_string(high) +
                                                    "] is empty or not a number");
    ScalarField changed(fields::kChanged, field.size());
    for (std::size_t i = 0; i < field.size(); ++i) {
        if (!field.hasValue(i))
            continue;
        const double v = field.value(i);
        changed.values()[i] = (v >= low && v <= high) ? 1.0f : 0.0f;
    }
    return changed;
}

ScalarField absoluteValues(const ScalarField& field)
{
    ScalarField out(field.name(), field.size());
    for (std::size_t i = 0; i < field.size(); ++i)
        if (field.hasValue(i))
            out.setValue(i, std::abs(field.value(i)));
    return out;
}

std::vector<std::uint8_t> selectionFromLabels(const ScalarField& labels)
{
    std::vector<std::uint8_t> selected(labels.size(), 0);
    for (std::size_t i = 0; i < labels.size(); ++i)
        selected[i] = labels.hasValue(i) && labels.value(i) > 0.5 ? 1 : 0;
    return selected;
}

KMeansResult kMeans(const ScalarField& field, const KMeansParams& params, ProgressObserver* progress)
{
    if (params.classes < 2 || params.classes > 64)
        throw Error(ErrorCode::InvalidArgument, "K-means: the number of classes must be in [2, 64], got " + std::to_string(params.classes));
    if (params.maxIterations < 1 || params.maxIterations > 10000)
        throw Error(ErrorCode::InvalidArgument, "K-means: the iteration cap must be in [1, 10000]");
    const auto k = static_cast<std::size_t>(params.classes);

    // In one dimension the nearest-centre partition is a set of k-1 cut points
    // (the mid-points of consecutive centres), so with the values sorted once and
    // their prefix sums, one Lloyd iteration costs k binary searches instead of a
    // pass over millions of points. The result is the same as the textbook loop.
    std::vector<double> sorted;
    sorted.reserve(field.size());
    for (std::size_t i = 0; i < field.size(); ++i)
        if (field.hasValue(i))
            sorted.push_back(field.value(i));
    if (sorted.size() < k)
        throw Error(ErrorCode::InvalidData, "K-means: field '" + field.name() + "' has " + std::to_string(sorted.size()) +
                                                " valid values, fewer than the " + std::to_string(k) + " classes");
    std::sort(sorted.begin(), sorted.end());
    std::vector<double> prefix(sorted.size() + 1, 0.0);
    for (std::size_t i = 0; i < sorted.size(); ++i)
        prefix[i + 1] = prefix[i] + sorted[i];

    KMeansResult result;
    const double lo = sorted.front(), hi = sorted.back();
    // Evenly spread over the value range (thesis §3.2.2), end points included.
    result.centres.resize(k);
    for (std::size_t j = 0; j < k; ++j)
        result.centres[j] = lo + (hi - lo) * static_cast<double>(j) / static_cast<double>(k - 1);

    ProgressTicker ticker(progress, "K-means", static_cast<std::uint64_t>(params.maxIterations));
    std::vector<std::size_t> ends(k, 0), previousEnds;
    for (int it = 0; it < params.maxIterations; ++it) {
        ticker.step();
        // Class j holds the sorted values in [ends[j-1], ends[j]); ties at a cut
        // go to the lower class.
        for (std::size_t j = 0; j + 1 < k; ++j) {
            const double cut = 0.5 * (result.centres[j] + result.centres[j + 1]);
            ends[j] = static_cast<std::size_t>(std::upper_bound(sorted.begin(), sorted.end(), cut) - sorted.begin());
        }
        ends[k - 1] = sorted.size();
        result.iterations = it + 1;
        if (ends == previousEnds) {
            result.converged = true;
            break;
        }
        previousEnds = ends;
        std::size_t begin = 0;
        for (std::size_t j = 0; j < k; ++j) {
            if (ends[j] > begin)
                result.centres[j] = (prefix[ends[j]] - prefix[begin]) / static_cast<double>(ends[j] - begin);
            begin = std::max(begin, ends[j]);
        }
        // Centres stay ordered: each is the mean of a run of sorted values that
        // lies after the previous class's run (an emptied class keeps its centre
        // between its neighbours' old centres, which a sort restores if needed).
        std::sort(result.centres.begin(), result.centres.end());
    }

    result.thresholds.resize(k - 1);
    for (std::size_t j = 0; j + 1 < k; ++j)
        result.thresholds[j] = 0.5 * (result.centres[j] + result.centres[j + 1]);
    std::size_t nearZero = 0;
    for (std::size_t j = 1; j < k; ++j)
        if (std::abs(result.centres[j]) < std::abs(result.centres[nearZero]))
            nearZero = j;

    result.classes = ScalarField(fields::kKMeansClass, field.size());
    result.changed = ScalarField(fields::kChanged, field.size());
    result.counts.assign(k, 0);
    for (std::size_t i = 0; i < field.size(); ++i) {
        if (!field.hasValue(i))
            continue;
        const double v = field.value(i);
        // Same tie rule as above: a value equal to a cut belongs to the lower class.
        const auto j = static_cast<std::size_t>(std::lower_bound(result.thresholds.begin(), result.thresholds.end(), v) -
                                                result.thresholds.begin());
        result.classes.values()[i] = static_cast<float>(j);
        result.changed.values()[i] = j == nearZero ? 0.0f : 1.0f;
        ++result.counts[j];
    }
    return result;
}

} // namespace scandiff
