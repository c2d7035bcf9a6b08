// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/CoordinateSystem.h>

#include <tbb/global_control.h>

#include <cmath>
#include <csignal>
#include <iomanip>
#include <cstdio>
#include <sstream>
#include <unistd.h>

namespace scandiff::cli {

namespace {

std::atomic<bool> interrupted{false};

extern "C" void onInterrupt(int)
{
    interrupted = true;
}

} // namespace

TerminalProgress::TerminalProgress() : draw_(::isatty(STDERR_FILENO) == 1)
{
    interrupted = false;
    std::signal(SIGINT, onInterrupt);
}

TerminalProgress::~TerminalProgress()
{
    finishLine();
    std::signal(SIGINT, SIG_DFL);
}

void TerminalProgress::finishLine()
{
    if (draw_ && lastPercent_ >= 0)
        std::fputc('\n', stderr);
    lastPercent_ = -1;
}

void TerminalProgress::beginStage(const std::string& title)
{
    finishLine();
    stage_ = title;
}

void TerminalProgress::report(double fraction)
{
    if (!draw_)
        return;
    const int percent = static_cast<int>(fraction * 100.0 + 0.5);
    if (percent == lastPercent_)
        return;
    lastPercent_ = percent;
    constexpr int width = 30;
    const int filled = percent * width / 100;
    std::fprintf(stderr, "\r%-40.40s [%.*s%*s] %3d%%", stage_.c_str(), filled, "##############################",
                 width - filled, "", percent);
    std::fflush(stderr);
}

bool TerminalProgress::cancelRequested() const
{
    return interrupted.load();
}

namespace {

std::string parameterHelp(const ParameterSpec& p)
{
    std::ostringstream s;
    s << p.description;
    if (!p.unit.empty())
        s << " (" << p.unit << ")";
    if (p.type == ParameterType::Integer || p.type == ParameterType::Real)
        s << "; range [" << p.minimum << ", " << p.maximum << "]";
    if (p.type == ParameterType::Choice) {
        s << "; one of:";
        for (const auto& c : p.choices)
            s << ' ' << c;
    }
    if (!p.suggestions.empty()) {
        s << "; e.g.";
        for (const auto& c : p.suggestions)
            s << ' ' << c;
    }
    if (!p.optional && !p.required && p.type != ParameterType::Boolean)
        s << "; default " << ParameterSpec::format(p.defaultValue);
    if (!p.alternativeGroup.empty())
        s << "; one of the alternatives '" << p.alternativeGroup << "'";
    return s.str();
}

} // namespace

std::map<std::string, CLI::Option*> addParameterOptions(CLI::App& command, const std::vector<ParameterSpec>& parameters,
                                                        std::shared_ptr<std::map<std::string, std::string>> userText)
{
    std::map<std::string, CLI::Option*> options;
    for (const auto& p : parameters) {
        const std::string name = p.name;
        CLI::Option* option = nullptr;
        if (p.type == ParameterType::Boolean) {
            // A switch that is on by default is turned off by --no-NAME.
            const bool onByDefault = std::get_if<bool>(&p.defaultValue) && std::get<bool>(p.defaultValue);
            option = command.add_flag_function(
                "--" + name + (onByDefault ? ",!--no-" + name : ""),
                [userText, name](std::int64_t count) { (*userText)[name] = count > 0 ? "true" : "false"; },
                parameterHelp(p) + (onByDefault ? " (on unless --no-" + name + ")" : ""));
        }
        else if (p.type == ParameterType::Text)
            option = command.add_option_function<std::vector<std::string>>(
                "--" + name,
                [userText, name](const std::vector<std::string>& values) {
                    std::string joined;
                    for (const auto& v : values)
                        joined += (joined.empty() ? "" : ";") + v;
                    (*userText)[name] = joined;
                },
                parameterHelp(p));
        else
            option = command.add_option_function<std::string>("--" + name, [userText, name](const std::string& v) { (*userText)[name] = v; },
                                                              parameterHelp(p));
        if (p.type == ParameterType::Text && p.commandLineValues > 1)
            option->expected(p.commandLineValues);
        if (p.required)
            option->required();
        options[name] = option;
    }
    return options;
}

void ThreadLimit::addOption(CLI::App& command, int& threads)
{
    command.add_option("--threads", threads, "Number of threads (default: all cores)")->check(CLI::Range(1, 1024));
}

ThreadLimit::ThreadLimit(int threads)
{
    if (threads > 0)
        control_ = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
}

ThreadLimit::~ThreadLimit() = default;

void checkOutputFile(const std::filesystem::path& file, const io::FormatRegistry* formats)
{
    const std::filesystem::path folder = file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
    std::error_code error;
    if (!std::filesystem::is_directory(folder, error))
        throw Error(ErrorCode::Io, "cannot write " + file.string() + ": the folder " + folder.string() + " does not exist");
    if (::access(folder.c_str(), W_OK) != 0)
        throw Error(ErrorCode::Io, "cannot write " + file.string() + ": the folder " + folder.string() + " is not writable");
    if (std::filesystem::is_directory(file, error))
        throw Error(ErrorCode::Io, "cannot write " + file.string() + ": it is a folder");
    if (formats) {
        const io::FormatHandler& handler = formats->forPath(file); // throws for an unknown extension
        if (!handler.writeCloud && !handler.writeMesh && !handler.writeClouds)
            throw Error(ErrorCode::Unsupported, "cannot write " + file.string() + ": scandiff reads " + handler.name + " but does not write it");
    }
}

void prepareOutputFolder(const std::filesystem::path& folder)
{
    std::error_code error;
    if (std::filesystem::exists(folder, error) && !std::filesystem::is_directory(folder, error))
        throw Error(ErrorCode::Io, "output folder " + folder.string() + " is a file");
    std::filesystem::create_directories(folder, error);
    if (error || !std::filesystem::is_directory(folder))
        throw Error(ErrorCode::Io, "cannot create the output folder " + folder.string() + (error ? ": " + error.message() : ""));
    if (::access(folder.c_str(), W_OK) != 0)
        throw Error(ErrorCode::Io, "the output folder " + folder.string() + " is not writable");
}

void printStatistics(std::ostream& out, const std::string& label, const DistanceStatistics& s)
{
    const auto flags = out.flags();
    const auto precision = out.precision();
    out << label << ": " << s.count << " values";
    if (s.count > 0)
        out << std::setprecision(6) << ", mean " << s.mean << ", std " << s.standardDeviation << ", min " << s.min
            << ", max " << s.max << ", RMS " << s.rms;
    out << '\n';
    out.flags(flags);
    out.precision(precision);
}

void ReadFlags::addTo(CLI::App& command)
{
    command.add_option("--columns", columns,
                       "ASCII files: column mapping, e.g. x,y,z,r,g,b,intensity (names: x y z r g b rf gf bf nx ny nz skip, "
                       "anything else is a scalar field)");
    command.add_option("--separator", separator, "ASCII files: column separator: , ; tab space");
    command.add_option("--skip-lines", skipLines, "ASCII files: number of leading lines to skip");
    command.add_option("--origin", origin, "Global shift to use, as X,Y,Z (default: chosen from the data)");
    command.add_option("--crs", crs,
                       "Coordinate reference system of inputs whose files give none (EPSG:2154, EPSG:2056+5728, a WKT): "
                       "carried to the outputs and into GeoTIFFs");
}

io::ReadOptions ReadFlags::toOptions(ProgressObserver* progress) const
{
    io::ReadOptions options;
    options.progress = progress;
    if (!columns.empty())
        options.asciiColumns = io::AsciiColumns{splitList(columns, ',')};
    if (!separator.empty()) {
        if (separator == "tab" || separator == "\\t")
            options.asciiSeparator = '\t';
        else if (separator == "space")
            options.asciiSeparator = ' ';
        else if (separator.size() == 1)
            options.asciiSeparator = separator[0];
        else
            throw Error(ErrorCode::InvalidArgument, "--separator: expected one character, 'tab' or 'space'");
    }
    if (skipLines >= 0)
        options.asciiSkipLines = static_cast<std::size_t>(skipLines);
    if (!origin.empty()) {
        const std::vector<double> v = parseNumberList(origin, "--origin");
        if (v.size() != 3)
            throw Error(ErrorCode::InvalidArgument, "--origin: expected X,Y,Z");
        const Eigen::Vector3d o(v[0], v[1], v[2]);
        options.origin = o;
    }
    if (!crs.empty())
        options.crsWkt = io::crsFromUserInput(crs);
    return options;
}

void WriteFlags::addTo(CLI::App& command)
{
    command.add_option("--encoding", encoding, "Output encoding: default, ascii, binary, binary-be, compressed (PCD)")
        ->check(CLI::IsMember({"default", "ascii", "binary", "binary-be", "compressed"}));
    command.add_option("--precision", precision, "ASCII output: decimals of the coordinates")->check(CLI::Range(0, 12));
}

io::WriteOptions WriteFlags::toOptions(ProgressObserver* progress) const
{
    io::WriteOptions options;
    options.progress = progress;
    options.asciiPrecision = precision;
    if (encoding == "ascii")
        options.encoding = io::Encoding::Ascii;
    else if (encoding == "binary")
        options.encoding = io::Encoding::BinaryLittleEndian;
    else if (encoding == "binary-be")
        options.encoding = io::Encoding::BinaryBigEndian;
    else if (encoding == "compressed")
        options.encoding = io::Encoding::BinaryCompressed;
    return options;
}

} // namespace scandiff::cli
