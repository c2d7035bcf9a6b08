// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The progress-and-cancel contract shared by every long operation.
//!
//! An operation receives a `ProgressObserver*` (null allowed). It may be called
//! from a worker thread, so implementations must be thread-safe; the CLI draws a
//! bar on stderr, the GUI forwards to a progress dialog with a Cancel button.
//! Algorithms do not talk to the observer directly in their loops: they use a
//! ProgressTicker, which turns "N steps done" into at most ~200 observer calls
//! and throws Error(Cancelled) when the observer asks to stop.

#include <atomic>
#include <cstdint>
#include <string>
#include <utility>

namespace scandiff {

class ProgressObserver
{
public:
    virtual ~ProgressObserver() = default;
    //! A new stage starts ("Reading points", "Sorting codes"...).
    virtual void beginStage(const std::string& title) = 0;
    //! Fraction of the current stage in [0, 1].
    virtual void report(double fraction) = 0;
    //! True once the user asked to stop; polled by ProgressTicker.
    virtual bool cancelRequested() const = 0;
};

//! Counts steps of one stage and forwards them to an observer sparingly.
//! Safe to call step() from several threads at once.
class ProgressTicker
{
public:
    ProgressTicker(ProgressObserver* observer, const std::string& stage, std::uint64_t totalSteps);
    //! Adds `count` steps; throws Error(Cancelled) if cancellation was requested.
    void step(std::uint64_t count = 1)
    {
        if (!observer_)
            return;
        const std::uint64_t done = done_.fetch_add(count, std::memory_order_relaxed) + count;
        if (done >= nextReport_.load(std::memory_order_relaxed))
            publish(done);
    }
    //! Throws Error(Cancelled) if cancellation was requested (for loops without steps).
    void checkCancel() const;

private:
    void publish(std::uint64_t done);

    ProgressObserver* observer_;
    std::uint64_t total_;
    std::uint64_t stride_;
    std::atomic<std::uint64_t> done_{0};
    std::atomic<std::uint64_t> nextReport_{0};
};

//! Forwards to another observer with every stage title prefixed, so a run that
//! repeats a computation (C2C both ways, a per-station loop) says which pass the
//! bar shows.
class PrefixedProgress : public ProgressObserver
{
public:
    PrefixedProgress(ProgressObserver* target, std::string prefix) : target_(target), prefix_(std::move(prefix)) {}
    void beginStage(const std::string& title) override { target_->beginStage(prefix_ + title); }
    void report(double fraction) override { target_->report(fraction); }
    bool cancelRequested() const override { return target_->cancelRequested(); }
    //! Null when `target` is null, so the result can be passed on as is.
    ProgressObserver* get() { return target_ ? this : nullptr; }

private:
    ProgressObserver* target_;
    std::string prefix_;
};

} // namespace scandiff
