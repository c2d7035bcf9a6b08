// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/Progress.h>

#include <gtest/gtest.h>

#include <thread>
#include <vector>

using namespace scandiff;

namespace {

class RecordingObserver : public ProgressObserver
{
public:
    void beginStage(const std::string& title) override { stages.push_back(title); }
    void report(double fraction) override
    {
        std::lock_guard<std::mutex> lock(mutex);
        fractions.push_back(fraction);
        if (cancelAfter > 0 && fraction >= cancelAfter)
            cancel = true;
    }
    bool cancelRequested() const override { return cancel.load(); }

    std::mutex mutex;
    std::vector<std::string> stages;
    std::vector<double> fractions;
    double cancelAfter = 0;
    std::atomic<bool> cancel{false};
};

} // namespace

TEST(ProgressTicker, ReportsSparinglyAndMonotonically)
{
    RecordingObserver observer;
    ProgressTicker ticker(&observer, "Counting", 1'000'000);
    for (int i = 0; i < 1'000'000; ++i)
        ticker.step();
    ASSERT_EQ(observer.stages, std::vector<std::string>{"Counting"});
    EXPECT_LE(observer.fractions.size(), 205u);
    EXPECT_GE(observer.fractions.size(), 100u);
    for (std::size_t i = 1; i < observer.fractions.size(); ++i)
        EXPECT_LE(observer.fractions[i - 1], observer.fractions[i]);
    EXPECT_DOUBLE_EQ(observer.fractions.back(), 1.0);
}

TEST(ProgressTicker, NullObserverCostsNothingAndNeverCancels)
{
    ProgressTicker ticker(nullptr, "nothing", 10);
    for (int i = 0; i < 100; ++i)
        ticker.step();
    EXPECT_NO_THROW(ticker.checkCancel());
}

TEST(ProgressTicker, CancellationThrowsCancelledFromWorkerThreads)
{
    RecordingObserver observer;
    observer.cancelAfter = 0.3;
    ProgressTicker ticker(&observer, "Working", 400'000);
    std::atomic<int> cancelledThreads{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 2; ++t)
        threads.emplace_back([&] {
            try {
                for (int i = 0; i < 200'000; ++i)
                    ticker.step();
            } catch (const Error& e) {
                if (e.code() == ErrorCode::Cancelled)
                    ++cancelledThreads;
            }
        });
    for (auto& t : threads)
        t.join();
    EXPECT_GE(cancelledThreads.load(), 1);
    EXPECT_THROW(ticker.checkCancel(), Error);
}
