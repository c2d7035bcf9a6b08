// SPDX-License-Identifier: GPL-3.0-or-later
//! How fast Cancel is heard, stage by stage, in a whole cloud-to-cloud run as
//! the workbench does it: read both files, compute (both ways if asked), write
//! the result. The observer records every poll of cancelRequested(); the longest
//! time between two polls (or between a stage's start and its first poll, or
//! its last poll and the next stage) bounds how long a Cancel pressed in that
//! stage can go unheard.
//! Usage: scandiff-cancel-latency COMPARED REFERENCE OUTPUT [NAME=VALUE ...]
//!        (c2c parameters, e.g. model=quadric both-ways=true)

#include <scandiff/core/Error.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/distance/DistanceParameters.h>
#include <scandiff/io/FileIO.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
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

} // namespace

int main(int argc, char** argv)
{
    if (argc < 4) {
        std::fprintf(stderr, "usage: %s COMPARED REFERENCE OUTPUT [NAME=VALUE ...]\n", argv[0]);
        return 2;
    }
    try {
        std::map<std::string, std::string> text;
        for (int i = 4; i < argc; ++i) {
            const std::string item = argv[i];
            const auto equals = item.find('=');
            text[item.substr(0, equals)] = equals == std::string::npos ? "true" : item.substr(equals + 1);
        }
        const scandiff::ParameterValues values = scandiff::resolveParameters(scandiff::cloudToCloudParameters(), text, "c2c");
        scandiff::io::FormatRegistry formats;
        scandiff::io::registerBuiltinFormats(formats);
        PollRecorder recorder;
        scandiff::io::ReadOptions read;
        read.progress = &recorder;
        scandiff::PointCloud compared = scandiff::io::readPointCloud(formats, argv[1], read);
        const scandiff::PointCloud reference = scandiff::io::readPointCloud(formats, argv[2], read);
        scandiff::CloudToCloudRun run = scandiff::runCloudToCloud(compared, reference, values, &recorder);
        compared.addField(std::move(run.forward.distance));
        scandiff::io::WriteOptions write;
        write.progress = &recorder;
        scandiff::io::writePointCloud(formats, compared, argv[3], write);
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
