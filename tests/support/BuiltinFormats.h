// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Every format scandiff reads and writes without a plugin, as the front ends
//! register them: for tests that go through io::readPointCloud and friends.

#include <scandiff/io/FileIO.h>

namespace scandiff::test {

inline io::FormatRegistry builtinFormats()
{
    io::FormatRegistry registry;
    io::registerBuiltinFormats(registry);
    return registry;
}

} // namespace scandiff::test
