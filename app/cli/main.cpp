// SPDX-License-Identifier: GPL-3.0-or-later
#include "Commands.h"

#include <iostream>

int main(int argc, char** argv)
{
    const scandiff::PluginRegistry registry = scandiff::makePluginRegistry();
    return scandiff::cli::runCli(argc, argv, registry, {std::cout, std::cerr});
}
