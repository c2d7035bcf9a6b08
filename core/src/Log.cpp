// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Log.h>

#include <iostream>
#include <mutex>

namespace scandiff {
namespace {

std::mutex& sinkMutex()
{
    static std::mutex mutex;
    return mutex;
}

LogSink& currentSink()
{
    static LogSink sink = [](LogLevel level, const std::string& message) {
        std::cerr << (level == LogLevel::Warning ? "warning: " : "") << message << '\n';
    };
    return sink;
}

void emit(LogLevel level, const std::string& message)
{
    std::lock_guard<std::mutex> lock(sinkMutex());
    if (currentSink())
        currentSink()(level, message);
}

} // namespace

LogSink setLogSink(LogSink sink)
{
    std::lock_guard<std::mutex> lock(sinkMutex());
    LogSink previous = std::move(currentSink());
    currentSink() = std::move(sink);
    return previous;
}

void logInfo(const std::string& message) { emit(LogLevel::Info, message); }
void logWarning(const std::string& message) { emit(LogLevel::Warning, message); }

} // namespace scandiff
