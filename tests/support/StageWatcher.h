// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! An observer for Cancel tests: counts the polls of cancelRequested() during
//! a stage whose title contains a given text, and asks to stop once that stage
//! has been polled a given number of times (0: never). A test can then check
//! that a long stage is polled inside, not only at its ends, and that Cancel
//! pressed during it stops the run.

#include <scandiff/core/Progress.h>

#include <atomic>
#include <mutex>
#include <string>

namespace scandiff::test {

class StageWatcher : public ProgressObserver
{
public:
    StageWatcher(std::string stage, std::size_t cancelAfterPolls) : stage_(std::move(stage)), cancelAfter_(cancelAfterPolls) {}

    void beginStage(const std::string& title) override
    {
        const std::lock_guard lock(mutex_);
        inStage_ = title.find(stage_) != std::string::npos;
        seen_ = seen_ || inStage_;
    }
    void report(double) override {}
    bool cancelRequested() const override
    {
        const std::lock_guard lock(mutex_);
        if (!inStage_)
            return false;
        ++polls_;
        return cancelAfter_ > 0 && polls_ >= cancelAfter_;
    }
    //! Polls counted in the watched stage so far.
    std::size_t polls() const
    {
        const std::lock_guard lock(mutex_);
        return polls_;
    }
    bool stageSeen() const
    {
        const std::lock_guard lock(mutex_);
        return seen_;
    }

private:
    std::string stage_;
    std::size_t cancelAfter_;
    mutable std::mutex mutex_;
    bool inStage_ = false, seen_ = false;
    mutable std::size_t polls_ = 0;
};

//! Counts every poll of cancelRequested(), whatever the stage, from any
//! thread; asks to stop from the `cancelAt`-th poll on (0: never). A first run
//! counts a task's polls; later runs cancel it at chosen ones.
class PollCounter : public ProgressObserver
{
public:
    explicit PollCounter(std::size_t cancelAt = 0) : cancelAt_(cancelAt) {}
    void beginStage(const std::string&) override {}
    void report(double) override {}
    bool cancelRequested() const override
    {
        const std::size_t poll = ++polls_;
        return cancelAt_ > 0 && poll >= cancelAt_;
    }
    std::size_t polls() const { return polls_; }

private:
    std::size_t cancelAt_;
    mutable std::atomic<std::size_t> polls_{0};
};

//! Asks to stop at the first poll, whatever the stage.
struct CancelAtOnce : ProgressObserver
{
    void beginStage(const std::string&) override {}
    void report(double) override {}
    bool cancelRequested() const override { return true; }
};

} // namespace scandiff::test
