// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What the workbench's window tests start from: the whole window with the
//! plugins, shown and exposed, and the demo pair (SCANDIFF_SAMPLE_DATA_DIR).

#include "MainWindow.h"

#include <scandiff/plugins/PluginRegistry.h>

#include <QString>
#include <QtTest>

namespace scandiff::test {

struct Workbench
{
    PluginRegistry registry = makePluginRegistry();
    gui::MainWindow window{registry};
    bool shown()
    {
        window.show();
        return QTest::qWaitForWindowExposed(&window);
    }
};

inline const QString kReference = SCANDIFF_SAMPLE_DATA_DIR "/demo/site-2019.ply";
inline const QString kCompared = SCANDIFF_SAMPLE_DATA_DIR "/demo/site-2024.ply";

} // namespace scandiff::test
