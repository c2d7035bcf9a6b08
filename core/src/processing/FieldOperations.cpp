// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/processing/FieldOperations.h>

#include "processing/PointNeighbourhoods.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/Histogram.h>

// muparser: a maintained expression parser with a bulk mode that evaluates an
// expression over arrays, made for this; writing our own would add nothing.
#include <muParser.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>

namespace scandiff {

namespace {

std::string trim(const std::string& s)
{
    const auto first = s.find_first_not_of(" \t");
    if (first == std::string::npos)
        return {};
    return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

const ScalarField& requireField(const PointCloud& cloud, const std::string& name, const char* what)
{
    const ScalarField* field = cloud.field(name);
    if (!field)
        throw Error(ErrorCode::InvalidArgument, std::string(what) + ": cloud '" + cloud.name + "' has no field '" + name + "'");
    return *field;
}

//! Where the values of one expression variable come from.
struct VariableSource
{
    enum class Kind { Field, Coordinate, Normal, Colour } kind;
    const ScalarField* field = nullptr;
    int component = 0;
};

} // namespace

std::pair<std::string, std::string> parseFieldAssignment(const std::string& text)
{
    for (std::size_t i = 0; i < text.size(); ++i) {
        if (text[i] != '=')
            continue;
        const bool comparison = (i > 0 && std::string("=!<>").find(text[i - 1]) != std::string::npos) ||
                                (i + 1 < text.size() && text[i + 1] == '=');
        if (comparison)
            continue;
        const std::string name = trim(text.substr(0, i)), expression = trim(text.substr(i + 1));
        if (name.empty() || expression.empty())
            break;
        return {name, expression};
    }
    throw Error(ErrorCode::InvalidArgument, "field: '" + text + "' is not NAME = EXPRESSION");
}

std::string expressionName(const std::string& fieldName)
{
    std::string out = fieldName;
    for (char& c : out)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_')
            c = '_';
    if (!out.empty() && std::isdigit(static_cast<unsigned char>(out.front())))
        out.insert(out.begin(), '_');
    return out;
}

ScalarField evaluateFieldExpression(const PointCloud& cloud, const std::string& expression, const std::string& resultName,
                                    ProgressObserver* progress)
{
    if (trim(expression).empty())
        throw Error(ErrorCode::InvalidArgument, "field: the expression is empty");
    // Every name the cloud offers; the parser reports which ones the expression uses.
    std::map<std::string, VariableSource> available;
    for (int a = 0; a < 3; ++a) {
        available[std::string(1, "xyz"[a])] = {VariableSource::Kind::Coordinate, nullptr, a};
        if (cloud.hasNormals())
            available[std::string("n") + "xyz"[a]] = {VariableSource::Kind::Normal, nullptr, a};
        if (cloud.hasColors())
            available[std::string(1, "rgb"[a])] = {VariableSource::Kind::Colour, nullptr, a};
    }
    // A field whose expression name is taken (another field's, or x, r, nx...)
    // is ambiguous: refused if the expression uses that name.
    std::map<std::string, std::string> ambiguous;
    for (const auto& f : cloud.fields()) {
        const std::string name = expressionName(f.name());
        const auto [it, fresh] = available.emplace(name, VariableSource{VariableSource::Kind::Field, &f, 0});
        if (!fresh)
            ambiguous[name] = f.name();
        (void)it;
    }

    constexpr int kBulk = 2048;
    struct Evaluator
    {
        mu::Parser parser;
        std::vector<std::pair<VariableSource, std::vector<double>>> variables;
        std::vector<double> results = std::vector<double>(kBulk);
    };
    // One parser per task (a parser is not thread-safe); each is checked the same way.
    const auto makeEvaluator = [&](Evaluator& e) {
        std::map<std::string, double*> unused;
        try {
            e.parser.SetExpr(expression);
            std::vector<double> probe(1);
            for (const auto& [name, source] : available)
                e.parser.DefineVar(name, probe.data());
            const mu::varmap_type used = e.parser.GetUsedVar();
            e.parser.ClearVar();
            e.variables.clear();
            e.variables.reserve(used.size());
            for (const auto& [name, ignored] : used) {
                (void)ignored;
                if (const auto clash = ambiguous.find(name); clash != ambiguous.end())
                    throw Error(ErrorCode::InvalidArgument,
                                "field: '" + name + "' in '" + expression + "' is ambiguous: field '" + clash->second +
                                    "' has the same name as another field or a coordinate (rename it first)");
                const auto source = available.find(name);
                if (source == available.end())
                    throw Error(ErrorCode::InvalidArgument,
                                "field: '" + name + "' in '" + expression + "' is not a field of '" + cloud.name +
                                    "' (fields are named with every character other than letters, digits and _ replaced by _; "
                                    "x y z, nx ny nz, r g b)");
                e.variables.emplace_back(source->second, std::vector<double>(kBulk));
                e.parser.DefineVar(name, e.variables.back().second.data());
            }
            e.parser.SetExpr(expression);
        } catch (const mu::Parser::exception_type& error) {
            throw Error(ErrorCode::InvalidArgument, "field: in '" + expression + "': " + error.GetMsg());
        }
    };
    {
        Evaluator check;
        makeEvaluator(check); // reports a bad expression before any work
    }

    const std::size_t n = cloud.size();
    ScalarField result(resultName, n);
    const auto& positions = cloud.positions();
    const Eigen::Vector3d origin = cloud.origin();
    std::vector<double> values(n);
    ProgressTicker ticker(progress, "Evaluating " + resultName, n);
    const std::size_t chunks = (n + kBulk - 1) / kBulk;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 8), [&](const tbb::blocked_range<std::size_t>& range) {
        Evaluator e;
        makeEvaluator(e);
        for (std::size_t chunk = range.begin(); chunk != range.end(); ++chunk) {
            const std::size_t begin = chunk * kBulk, count = std::min<std::size_t>(kBulk, n - begin);
            for (auto& [source, array] : e.variables)
                for (std::size_t j = 0; j < count; ++j) {
                    const std::size_t i = begin + j;
                    switch (source.kind) {
                    case VariableSource::Kind::Field: array[j] = source.field->value(i); break;
                    case VariableSource::Kind::Coordinate:
                        array[j] = origin[source.component] + static_cast<double>(positions[i][source.component]);
                        break;
                    case VariableSource::Kind::Normal: array[j] = cloud.normals()[i][source.component]; break;
                    case VariableSource::Kind::Colour: {
                        const Rgb8& c = cloud.colors()[i];
                        array[j] = source.component == 0 ? c.r : source.component == 1 ? c.g : c.b;
                        break;
                    }
                    }
                }
            e.parser.Eval(e.results.data(), static_cast<int>(count));
            // A point without a value in a field the expression uses gets none,
            // whatever the expression does with it (a comparison with NaN is
            // false, so "f > 2 ? 1 : 0" would otherwise give it 0).
            for (const auto& [source, array] : e.variables)
                if (source.kind == VariableSource::Kind::Field)
                    for (std::size_t j = 0; j < count; ++j)
                        if (std::isnan(array[j]))
                            e.results[j] = std::numeric_limits<double>::quiet_NaN();
            std::copy_n(e.results.begin(), count, values.begin() + static_cast<std::ptrdiff_t>(begin));
            ticker.step(count);
        }
    });
    // Stored around the mean of the finite values, so large results (a GPS
    // time, a global coordinate) keep their precision in float.
    double sum = 0;
    std::size_t finite = 0;
    for (double v : values)
        if (std::isfinite(v)) {
            sum += v;
            ++finite;
        }
    const double offset = finite > 0 && std::abs(sum / static_cast<double>(finite)) > 1e4 ? std::floor(sum / static_cast<double>(finite)) : 0.0;
    result.setOffset(offset);
    bool floatsHold = true;
    for (std::size_t i = 0; i < n; ++i) {
        const float f = std::isfinite(values[i]) ? static_cast<float>(values[i] - offset) : std::numeric_limits<float>::quiet_NaN();
        result.values()[i] = f;
        floatsHold = floatsHold && (std::isnan(f) || offset + static_cast<double>(f) == values[i]);
    }
    // Results the floats around the offset do not give back (identifiers past
    // 2^24, a time to the microsecond, a global coordinate) are kept exactly,
    // in float residuals or doubles, as the readers keep such values.
    if (!floatsHold) {
        result.keepDoubles();
        for (std::size_t i = 0; i < n; ++i)
            result.doubles()[i] = std::isfinite(values[i]) ? values[i] : std::numeric_limits<double>::quiet_NaN();
        result.compact();
    }
    return result;
}

ScalarField gaussianSmoothing(const PointCloud& cloud, const std::string& fieldName, double sigma, const std::string& resultName,
                              ProgressObserver* progress)
{
    const ScalarField& field = requireField(cloud, fieldName, "smoothing");
    if (!(sigma > 0) || !std::isfinite(sigma))
        throw Error(ErrorCode::InvalidArgument, "smoothing: sigma must be > 0");
    ScalarField result(resultName, cloud.size());
    result.setOffset(field.offset());
    if (cloud.empty())
        return result;
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    const double inverse = 1.0 / (2 * sigma * sigma);
    ProgressTicker ticker(progress, "Gaussian smoothing", cloud.size());
    // Neighbours beyond 3 sigma weigh less than 1.2 % of the point itself.
    detail::forEachPointNeighbourhood(tree, 3 * sigma, 0, ticker, [&](std::size_t i, const octree::Neighbour* list, std::size_t count) {
        if (!field.hasValue(i))
            return;
        double sum = 0, weights = 0;
        for (std::size_t j = 0; j < count; ++j) {
            const std::uint32_t k = list[j].index;
            if (!field.hasValue(k))
                continue;
            const double w = std::exp(-static_cast<double>(list[j].squaredDistance) * inverse);
            sum += w * field.values()[k];
            weights += w;
        }
        result.values()[i] = static_cast<float>(sum / weights);
    });
    return result;
}

std::vector<Rgb8> coloursFromField(const ScalarField& field, const ColourScale& scale, double low, double high, Rgb8 noValue)
{
    std::vector<Rgb8> colours(field.size());
    const double span = high - low;
    for (std::size_t i = 0; i < field.size(); ++i) {
        if (!field.hasValue(i)) {
            colours[i] = noValue;
            continue;
        }
        const double t = span > 0 ? (field.value(i) - low) / span : 0.5;
        const auto c = scale.colourAt(t);
        colours[i] = Rgb8{c[0], c[1], c[2]};
    }
    return colours;
}

ColourChannel parseColourChannel(const std::string& name)
{
    if (name == "luminance")
        return ColourChannel::Luminance;
    if (name == "red")
        return ColourChannel::Red;
    if (name == "green")
        return ColourChannel::Green;
    if (name == "blue")
        return ColourChannel::Blue;
    if (name == "mean")
        return ColourChannel::Mean;
    throw Error(ErrorCode::InvalidArgument, "colours to field: channel '" + name + "' is not luminance, red, green, blue or mean");
}

ScalarField fieldFromColours(const PointCloud& cloud, ColourChannel channel, const std::string& resultName)
{
    if (!cloud.hasColors())
        throw Error(ErrorCode::InvalidArgument, "colours to field: cloud '" + cloud.name + "' has no colours");
    ScalarField result(resultName, cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Rgb8& c = cloud.colors()[i];
        double v = 0;
        switch (channel) {
        case ColourChannel::Luminance: v = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; break;
        case ColourChannel::Red: v = c.r; break;
        case ColourChannel::Green: v = c.g; break;
        case ColourChannel::Blue: v = c.b; break;
        case ColourChannel::Mean: v = (c.r + c.g + c.b) / 3.0; break;
        }
        result.values()[i] = static_cast<float>(v);
    }
    return result;
}

Table fieldHistogram(const ScalarField& field, int bins, std::optional<std::pair<double, double>> range)
{
    if (bins < 1)
        throw Error(ErrorCode::InvalidArgument, "histogram: at least one bin is needed");
    Table table;
    table.columns = {"bin_min", "bin_max", "count"};
    double low = 0, high = 0;
    std::vector<std::size_t> counts(static_cast<std::size_t>(bins), 0);
    if (range) {
        low = range->first;
        high = range->second;
        if (!(low < high) || !std::isfinite(low) || !std::isfinite(high))
            throw Error(ErrorCode::InvalidArgument, "histogram: the range must be finite with min < max");
        const double toBin = bins / (high - low);
        for (std::size_t i = 0; i < field.size(); ++i) {
            const double v = field.value(i);
            if (!(v >= low && v <= high))
                continue;
            const auto bin = std::min(static_cast<std::size_t>((v - low) * toBin), counts.size() - 1);
            ++counts[bin];
        }
    } else {
        const Histogram h = computeHistogram(field.values().data(), field.size(), field.offset(), bins);
        low = h.min;
        high = h.max;
        counts = h.counts;
    }
    const double width = (high - low) / bins;
    for (int b = 0; b < bins; ++b)
        table.rows.push_back({low + b * width, b + 1 == bins ? high : low + (b + 1) * width,
                              static_cast<double>(counts[static_cast<std::size_t>(b)])});
    return table;
}

FilterByValueResult filterByValue(const PointCloud& cloud, const FilterByValueParams& params)
{
    const ScalarField* field = cloud.field(params.field);
    if (!field)
        throw Error(ErrorCode::InvalidArgument, "filter: cloud '" + cloud.name + "' has no field '" + params.field + "'");
    if (!(params.low <= params.high))
        throw Error(ErrorCode::InvalidArgument, "filter: the range's lower bound is above its upper bound");
    FilterByValueResult result;
    for (std::size_t i = 0; i < field->size(); ++i) {
        if (!field->hasValue(i)) {
            ++result.withoutValue;
            continue;
        }
        const double v = field->value(i);
        const bool inside = v >= params.low && v <= params.high;
        if (inside != params.outside)
            result.kept.push_back(i);
    }
    return result;
}

} // namespace scandiff
