// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/Progress.h>

#include <algorithm>

namespace scandiff {

namespace {
// About 200 reports per stage: smooth for a bar, negligible for the loop.
constexpr std::uint64_t kReportsPerStage = 200;
} // namespace

ProgressTicker::ProgressTicker(ProgressObserver* observer, const std::string& stage, std::uint64_t totalSteps)
    : observer_(observer), total_(std::max<std::uint64_t>(totalSteps, 1)),
      stride_(std::max<std::uint64_t>(total_ / kReportsPerStage, 1))
{
    nextReport_ = stride_;
    if (observer_) {
        observer_->beginStage(stage);
        observer_->report(0.0);
        checkCancel();
    }
}

void ProgressTicker::checkCancel() const
{
    if (observer_ && observer_->cancelRequested())
        throw Error(ErrorCode::Cancelled, "cancelled by the user");
}

void ProgressTicker::publish(std::uint64_t done)
{
    // The thresholds are the stride's multiples, and each one crossed is
    // claimed by exactly one thread, which reports and polls for it: a run
    // polls as many times as thresholds lie below its total, however the
    // threads batched their steps. (Moving the threshold to done + stride
    // made the count depend on that batching, so a Cancel set at the last
    // poll of one run was never reached by the next.)
    std::uint64_t expected = nextReport_.load(std::memory_order_relaxed);
    while (done >= expected) {
        if (nextReport_.compare_exchange_weak(expected, expected + stride_, std::memory_order_relaxed)) {
            observer_->report(std::min(1.0, static_cast<double>(expected) / static_cast<double>(total_)));
            checkCancel();
            expected += stride_;
        }
    }
}

} // namespace scandiff
