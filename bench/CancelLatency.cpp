// SPDX-License-Identifier: GPL-3.0-or-later
//! How fast Cancel is heard, stage by stage, in a whole run as the workbench
//! does it: read the files, compute, write the result. The observer records
//! every poll of cancelRequested(); the longest time between two polls (or
//! between a stage's start and its first poll, or its last poll and the next
//! stage) bounds how long a Cancel pressed in that stage can go unheard.
//! Usage: scandiff-cancel-latency c2c COMPARED REFERENCE OUTPUT [NAME=VALUE ...]
//!        scandiff-cancel-latency TOOL ROLE=FILE ... [NAME=VALUE ...]
//! The second form runs any tool of the registry (`scandiff-cli tools`): its
//! inputs by role (e.g. input=a.ply, reference=b.ply), its parameters by name;
//! the first cloud output is written to /dev/null through the PLY writer.

#include <scandiff/core/Error.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/distance/DistanceParameters.h>
#include <scandiff/io/FileIO.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

class PollRecorder : public scandiff::ProgressObserver
{
public:
    struct Stage
    {
        std::string title;
        double start = 0, end = 0, lastPoll = 0, longestSilence = 0;
        std::size_t polls = 0;
    };

    void beginStage(const std::string& title) override
    {
        const std::lock_guard lock(mutex_);
        const double now = seconds();
        close(now);
        stages_.push_back({title, now, now, now, 0, 0});
    }
    void report(double) override {}
    bool cancelRequested() const override
    {
        const std::lock_guard lock(mutex_);
        const double now = seconds();
        if (!stages_.empty()) {
            Stage& stage = stages_.back();
            stage.longestSilence = std::max(stage.longestSilence, now - stage.lastPoll);
            stage.lastPoll = now;
            ++stage.polls;
        }
        return false;
    }
    void finish() { close(seconds()); }
    const std::vector<Stage>& stages() const { return stages_; }

private:
    double seconds() const { return std::chrono::duration<double>(Clock::now() - begin_).count(); }
    void close(double now)
    {
        if (stages_.empty())
            return;
        Stage& stage = stages_.back();
        stage.longestSilence = std::max(stage.longestSilence, now - stage.lastPoll);
        stage.end = now;
    }

    Clock::time_point begin_ = Clock::now();
    mutable std::mutex mutex_;
    mutable std::vector<Stage> stages_;
};

//! NAME=VALUE arguments from `first` on; names listed in `roles` go to `files`.
std::map<std::string, std::string> splitArguments(int argc, char** argv, int first, const scandiff::ToolSpec* tool,
                                                  std::vector<std::pair<std::string, std::string>>& files)
{
    std::map<std::string, std::string> text;
    for (int i = first; i < argc; ++i) {
        const std::string item = argv[i];
        const auto equals = item.find('=');
        const std::string name = item.substr(0, equals);
        const std::string value = equals == std::string::npos ? "true" : item.substr(equals + 1);
        if (tool && tool->input(name))
            files.emplace_back(name, value);
        else
            text[name] = value;
    }
    return text;
}

void runCloudToCloud(int argc, char** argv, PollRecorder& recorder)
{
    std::vector<std::pair<std::string, std::string>> unused;
    const auto text = splitArguments(argc, argv, 5, nullptr, unused);
    const scandiff::ParameterValues values = scandiff::resolveParameters(scandiff::cloudToCloudParameters(), text, "c2c");
    scandiff::io::FormatRegistry formats;
    scandiff::io::registerBuiltinFormats(formats);
    scandiff::io::ReadOptions read;
    read.progress = &recorder;
    scandiff::PointCloud compared = scandiff::io::readPointCloud(formats, argv[2], read);
    const scandiff::PointCloud reference = scandiff::io::readPointCloud(formats, argv[3], read);
    scandiff::CloudToCloudRun run = scandiff::runCloudToCloud(compared, reference, values, &recorder);
    compared.addField(std::move(run.forward.distance));
    scandiff::io::WriteOptions write;
    write.progress = &recorder;
    scandiff::io::writePointCloud(formats, compared, argv[4], write);
}

void runTool(int argc, char** argv, PollRecorder& recorder)
{
    const scandiff::PluginRegistry registry = scandiff::makePluginRegistry();
    const scandiff::ToolSpec* tool = registry.tools.find(argv[1]);
    if (!tool)
        throw scandiff::Error(scandiff::ErrorCode::InvalidArgument, std::string("no tool named ") + argv[1]);
    std::vector<std::pair<std::string, std::string>> files;
    const auto text = splitArguments(argc, argv, 2, tool, files);
    const scandiff::ParameterValues values = tool->resolve(text);
    scandiff::io::ReadOptions read;
    read.progress = &recorder;
    std::vector<std::unique_ptr<scandiff::Entity>> entities;
    scandiff::ToolInputs inputs;
    for (const auto& [role, path] : files) {
        entities.push_back(std::make_unique<scandiff::Entity>(scandiff::io::readFile(registry.formats, path, read)));
        inputs.add(role, *entities.back());
    }
    scandiff::ToolResult result = tool->execute(inputs, values, &recorder);
    for (auto& output : result.outputs)
        if (const auto* cloud = std::get_if<scandiff::PointCloud>(&output.data)) {
            scandiff::io::WriteOptions write;
            write.progress = &recorder;
            scandiff::io::writePointCloud(registry.formats, *cloud, "/tmp/scandiff-cancel-latency-output.ply", write);
            std::remove("/tmp/scandiff-cancel-latency-output.ply");
            break;
        }
}

} // namespace

int main(int argc, char** argv)
{
    const bool cloudToCloud = argc >= 2 && std::string(argv[1]) == "c2c";
    if (argc < 3 || (cloudToCloud && argc < 5)) {
        std::fprintf(stderr,
                     "usage: %s c2c COMPARED REFERENCE OUTPUT [NAME=VALUE ...]\n"
                     "       %s TOOL ROLE=FILE ... [NAME=VALUE ...]\n",
                     argv[0], argv[0]);
        return 2;
    }
    try {
        PollRecorder recorder;
        if (cloudToCloud)
            runCloudToCloud(argc, argv, recorder);
        else
            runTool(argc, argv, recorder);
        recorder.finish();

        std::printf("%-66s %9s %9s %14s\n", "stage", "seconds", "polls", "longest gap s");
        double worst = 0, total = 0;
        for (const auto& stage : recorder.stages()) {
            std::printf("%-66s %9.3f %9zu %14.3f\n", stage.title.c_str(), stage.end - stage.start, stage.polls, stage.longestSilence);
            worst = std::max(worst, stage.longestSilence);
            total = stage.end;
        }
        std::printf("whole run %.3f s; Cancel unheard for at most %.3f s\n", total, worst);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
