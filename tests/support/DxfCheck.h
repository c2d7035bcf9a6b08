// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! DXF files checked by an independent reader: tests/io/check_dxf.py loads a
//! file with ezdxf, audits it and prints the entity counts per type and layer.

#include <cstdio>
#include <filesystem>
#include <map>
#include <regex>
#include <string>
#include <sys/wait.h>

#include <gtest/gtest.h>

#include "TestSupport.h"

#ifndef SCANDIFF_TEST_SCRIPTS_DIR
#error "SCANDIFF_TEST_SCRIPTS_DIR must be defined by CMake (the absolute path of tests/io)"
#endif
// The interpreter that runs check_dxf.py; the script itself falls back to the
// system python3 when this one lacks ezdxf.
#ifndef SCANDIFF_PYTHON
#define SCANDIFF_PYTHON "python3"
#endif

namespace scandiff::test {

struct DxfCheck
{
    int exitStatus = -1;
    std::string version;
    std::map<std::string, int> counts; // "TYPE", "TYPE@LAYER" and "total"

    int count(const std::string& key) const
    {
        const auto it = counts.find(key);
        return it == counts.end() ? 0 : it->second;
    }
};

//! Runs check_dxf.py on `file`: its exit status and the counts it prints.
inline DxfCheck checkDxf(const std::filesystem::path& file)
{
    const std::string command = std::string(SCANDIFF_PYTHON) + " '" +
                                (std::filesystem::path(SCANDIFF_TEST_SCRIPTS_DIR) / "check_dxf.py").string() + "' '" +
                                file.string() + "'";
    DxfCheck check;
    const CommandOutcome outcome = runCommand(command);
    if (!outcome.started) {
        ADD_FAILURE() << "cannot run " << command;
        return check;
    }
    const std::string& output = outcome.output;
    check.exitStatus = outcome.status;

    // The script prints one flat JSON object: "key": integer, and "version": "ACxxxx".
    static const std::regex number("\"([^\"]+)\": (\\d+)");
    for (auto it = std::sregex_iterator(output.begin(), output.end(), number); it != std::sregex_iterator(); ++it)
        check.counts[(*it)[1].str()] = std::stoi((*it)[2].str());
    std::smatch version;
    if (std::regex_search(output, version, std::regex("\"version\": \"([^\"]+)\"")))
        check.version = version[1].str();
    return check;
}

} // namespace scandiff::test
