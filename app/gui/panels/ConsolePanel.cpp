// SPDX-License-Identifier: GPL-3.0-or-later
#include "panels/ConsolePanel.h"

#include <scandiff/core/Log.h>

#include <QMetaObject>
#include <QTime>

#include <iostream>

namespace scandiff::gui {

ConsolePanel::ConsolePanel(QWidget* parent) : QPlainTextEdit(parent)
{
    setReadOnly(true);
    setMaximumBlockCount(5000);
    setLineWrapMode(QPlainTextEdit::WidgetWidth);
    QFont mono("Monospace");
    mono.setStyleHint(QFont::TypeWriter);
    setFont(mono);
    // Tools log from worker threads: the message is queued to the GUI thread.
    // The sink is replaced (under the log's mutex) before this panel dies, so
    // `this` is alive whenever the sink runs.
    previousSink_ = setLogSink([this](LogLevel level, const std::string& message) {
        std::cerr << (level == LogLevel::Warning ? "warning: " : "") << message << '\n';
        const QString text = QString::fromStdString(message);
        QMetaObject::invokeMethod(this, [this, level, text] { level == LogLevel::Warning ? warning(text) : info(text); },
                                  Qt::QueuedConnection);
    });
}

ConsolePanel::~ConsolePanel() { setLogSink(std::move(previousSink_)); }

void ConsolePanel::info(const QString& message)
{
    appendHtml(QString("<span style='color:#888'>[%1]</span> %2").arg(QTime::currentTime().toString("HH:mm:ss"), message.toHtmlEscaped()));
}

void ConsolePanel::warning(const QString& message)
{
    appendHtml(QString("<span style='color:#888'>[%1]</span> <span style='color:#c80'>warning: %2</span>")
                   .arg(QTime::currentTime().toString("HH:mm:ss"), message.toHtmlEscaped()));
}

void ConsolePanel::error(const QString& message)
{
    appendHtml(QString("<span style='color:#888'>[%1]</span> <span style='color:#d22'>error: %2</span>")
                   .arg(QTime::currentTime().toString("HH:mm:ss"), message.toHtmlEscaped()));
}

} // namespace scandiff::gui
