// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Helpers shared by the test suites: data paths (configured by CMake), a
//! per-test temporary folder, and small file utilities.

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include <sys/wait.h>

#include <gtest/gtest.h>

#ifndef SCANDIFF_TEST_DATA_DIR
#error "SCANDIFF_TEST_DATA_DIR must be defined by CMake"
#endif

namespace scandiff::test {

//! A file of tests/data.
inline std::filesystem::path dataPath(const std::string& name)
{
    return std::filesystem::path(SCANDIFF_TEST_DATA_DIR) / name;
}

//! A fresh folder for the current test, removed at the start of the next run.
inline std::filesystem::path tempDir()
{
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? std::string(info->test_suite_name()) + "_" + info->name() : "scandiff";
    for (char& c : name)
        if (c == '/')
            c = '_';
    const auto dir = std::filesystem::temp_directory_path() / "scandiff-tests" / name;
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

inline void writeText(const std::filesystem::path& path, const std::string& text)
{
    std::ofstream out(path, std::ios::binary);
    out << text;
}

inline std::string readBytes(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

//! What a shell command printed on its standard output and its exit status
//! (-1 when it did not exit normally).
struct CommandOutcome
{
    bool started = false; //!< false when the shell could not be started
    int status = -1;
    std::string output;
};

inline CommandOutcome runCommand(const std::string& command)
{
    CommandOutcome outcome;
    FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe)
        return outcome;
    outcome.started = true;
    char buffer[4096];
    while (const std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe))
        outcome.output.append(buffer, n);
    const int status = ::pclose(pipe);
    outcome.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return outcome;
}

//! The code of the scandiff::Error that `f` throws; Internal if it throws none.
inline ErrorCode errorCodeOf(const std::function<void()>& f)
{
    try {
        f();
    } catch (const Error& e) {
        return e.code();
    }
    return ErrorCode::Internal;
}

//! Collects what is logged while alive, so a test can check it and the
//! output stays quiet: the warnings, and every message.
class CapturedLog
{
public:
    CapturedLog()
    {
        previous_ = setLogSink([this](LogLevel level, const std::string& message) {
            if (level == LogLevel::Warning)
                warnings.push_back(message);
            messages.push_back(message);
        });
    }
    ~CapturedLog() { setLogSink(std::move(previous_)); }
    CapturedLog(const CapturedLog&) = delete;
    CapturedLog& operator=(const CapturedLog&) = delete;

    //! Whether a message says `words`.
    bool has(const std::string& words) const
    {
        for (const std::string& m : messages)
            if (m.find(words) != std::string::npos)
                return true;
        return false;
    }

    std::vector<std::string> warnings, messages;

private:
    LogSink previous_;
};

//! Expects `read` to throw scandiff::Error with `code`, its message naming
//! `path` and saying `words`.
template <class Fn>
void expectError(Fn&& read, ErrorCode code, const std::filesystem::path& path, const std::string& words)
{
    try {
        read();
        ADD_FAILURE() << "no error for " << path << " (expected: " << words << ")";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), code) << e.what();
        EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
}

} // namespace scandiff::test
