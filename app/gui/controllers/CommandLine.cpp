// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/CommandLine.h"

#include <QDir>
#include <QFileInfo>
#include <QRegularExpression>

#include <algorithm>

namespace scandiff::gui {

QString shellQuoted(const QString& word)
{
    static const QRegularExpression plain("^[A-Za-z0-9_./:=,+@%-]+$");
    if (plain.match(word).hasMatch())
        return word;
    QString quoted = word;
    quoted.replace("'", "'\\''");
    return "'" + quoted + "'";
}

CommandLine::CommandLine(const Document& document, const QString& command) : document_(document) { words_ << command; }

CommandLine& CommandLine::word(const QString& text)
{
    words_ << text;
    return *this;
}

CommandLine& CommandLine::file(const Document::Item& item)
{
    // A scan of a multi-scan file shares the file with its group: the file is not it.
    const Document::Item* parent = document_.find(item.parent);
    const bool partOfItsFile = parent && parent->isGroup() && parent->sourcePath == item.sourcePath;
    if (!item.sourcePath.isEmpty() && !item.unsaved && !partOfItsFile) {
        words_ << shellQuoted(item.sourcePath);
        return *this;
    }
    QString name = item.name;
    name.replace(QRegularExpression("[^A-Za-z0-9_.-]+"), "_");
    const QString file = name + ".ply";
    words_ << shellQuoted(file);
    if (!toExport_.contains(file))
        toExport_ << file;
    return *this;
}

CommandLine& CommandLine::outputBeside(const QString& option, const Document::Item& item, const QString& suffix, const QString& extension)
{
    QString stem = item.sourcePath.isEmpty() ? item.name : QFileInfo(item.sourcePath).completeBaseName();
    stem.replace(QRegularExpression("[^A-Za-z0-9_.-]+"), "_");
    const QString folder = item.sourcePath.isEmpty() ? QString() : QFileInfo(item.sourcePath).absolutePath();
    const QString path = folder.isEmpty() ? stem + suffix + extension : QDir(folder).filePath(stem + suffix + extension);
    words_ << option << shellQuoted(path);
    return *this;
}

CommandLine& CommandLine::options(const std::map<std::string, std::string>& values, const std::vector<ParameterSpec>& specs)
{
    for (const auto& [name, value] : values) {
        const auto spec = std::find_if(specs.begin(), specs.end(), [&](const ParameterSpec& s) { return s.name == name; });
        const QString option = "--" + QString::fromStdString(name);
        const bool isSwitch = spec != specs.end() ? spec->type == ParameterType::Boolean : value == "true" || value == "false";
        if (isSwitch) {
            const bool onByDefault = spec != specs.end() && std::get_if<bool>(&spec->defaultValue) && std::get<bool>(spec->defaultValue);
            if (value == "true" && !onByDefault)
                words_ << option;
            else if (value == "false" && onByDefault)
                words_ << "--no-" + QString::fromStdString(name);
            continue;
        }
        const QString text = QString::fromStdString(value);
        if (spec != specs.end() && spec->type == ParameterType::Text && spec->commandLineValues > 1) {
            // "A B", "A,B" or "A;B": the option's values, one word each.
            words_ << option;
            for (const QString& part : text.split(QRegularExpression("[;,\\s]+"), Qt::SkipEmptyParts))
                words_ << shellQuoted(part);
            continue;
        }
        const QStringList parts = text.split(';', Qt::SkipEmptyParts);
        if (spec != specs.end() && spec->type == ParameterType::Text && parts.size() > 1) {
            for (const QString& part : parts)
                words_ << option << shellQuoted(part);
            continue;
        }
        words_ << option << shellQuoted(QString::fromStdString(value));
    }
    return *this;
}

QString CommandLine::text() const
{
    QString line = words_.join(' ');
    if (!toExport_.isEmpty())
        line += "  # " + QObject::tr("export %1 first: in no file yet").arg(toExport_.join(", "));
    return line;
}

} // namespace scandiff::gui
