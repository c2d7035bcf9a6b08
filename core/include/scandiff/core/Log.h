// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Log sink for warnings and information that do not stop an operation.
//! The default sink writes to stderr; the GUI installs one that feeds its console.

#include <functional>
#include <string>

namespace scandiff {

enum class LogLevel { Info, Warning };

using LogSink = std::function<void(LogLevel, const std::string&)>;

//! Replaces the process-wide sink; returns the previous one. Thread-safe.
LogSink setLogSink(LogSink sink);
void logInfo(const std::string& message);
void logWarning(const std::string& message);

} // namespace scandiff
