// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Pieces shared by the commands of scandiff-cli.

#include <scandiff/core/Progress.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/ToolRegistry.h>
#include <scandiff/core/distance/DistanceStatistics.h>
#include <scandiff/io/FileIO.h>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <atomic>
#include <map>
#include <memory>
#include <string>

namespace scandiff::cli {

//! A progress bar on stderr, drawn only when stderr is a terminal. Ctrl-C asks
//! the running operation to cancel (it then stops cleanly, leaving no partial file).
class TerminalProgress : public ProgressObserver
{
public:
    TerminalProgress();
    ~TerminalProgress() override;
    void beginStage(const std::string& title) override;
    void report(double fraction) override;
    bool cancelRequested() const override;

private:
    void finishLine();
    bool draw_;
    std::string stage_;
    int lastPercent_ = -1;
};

//! Options of how files are read, shared by every command that reads one.
struct ReadFlags
{
    std::string columns;   //!< "x,y,z,intensity"
    std::string separator; //!< "," ";" "tab" "space"
    int skipLines = -1;
    std::string origin;    //!< "X,Y,Z"
    std::string crs;       //!< "EPSG:2154", a WKT...
    void addTo(CLI::App& command);
    //! Throws Error(InvalidArgument) for malformed values.
    io::ReadOptions toOptions(ProgressObserver* progress) const;
};

struct WriteFlags
{
    std::string encoding = "default";
    int precision = 6;
    void addTo(CLI::App& command);
    io::WriteOptions toOptions(ProgressObserver* progress) const;
};

//! One option per declared parameter, named "--NAME": booleans are flags,
//! Text options may be repeated (their values joined by ';'), the rest take a
//! value. What the user typed lands in `userText`, keyed by parameter name, for
//! resolveParameters(). Returns the options by parameter name (for excludes()).
std::map<std::string, CLI::Option*> addParameterOptions(CLI::App& command, const std::vector<ParameterSpec>& parameters,
                                                        std::shared_ptr<std::map<std::string, std::string>> userText);

//! --threads N: limits TBB's worker threads for the lifetime of the object.
class ThreadLimit
{
public:
    //! Adds the --threads option to a command; 0 (the default) means all cores.
    static void addOption(CLI::App& command, int& threads);
    explicit ThreadLimit(int threads);
    ~ThreadLimit();

private:
    std::unique_ptr<tbb::global_control> control_;
};

//! Checks, before any computation, that `file` can be written: its folder
//! exists and is writable, it is not a folder, and (with `formats`) its
//! extension names a format scandiff writes. Throws Error(Io or Unsupported)
//! naming the file, so a long run never ends on a refused output.
void checkOutputFile(const std::filesystem::path& file, const io::FormatRegistry* formats = nullptr);
//! Creates an output folder (and its parents) when missing; throws
//! Error(Io) when it cannot or when the path names a file.
void prepareOutputFolder(const std::filesystem::path& folder);

//! "label: N values, mean ..., std ..., min ..., max ..., RMS ..." on one line.
void printStatistics(std::ostream& out, const std::string& label, const DistanceStatistics& statistics);

} // namespace scandiff::cli
