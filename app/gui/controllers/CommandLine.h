// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The console's "equivalent command line" of a run from the workbench: a
//! `scandiff-cli` command that runs as is in a shell (files quoted, outputs
//! named, options as the CLI spells them) and gives the same numbers.

#include "document/Document.h"

#include <scandiff/core/ToolRegistry.h>

#include <QString>
#include <QStringList>

#include <map>
#include <string>
#include <vector>

namespace scandiff::gui {

//! A word a POSIX shell reads back as itself: quoted when it holds anything
//! but letters, digits and _ . / : = , + - @ %.
QString shellQuoted(const QString& word);

//! Builds one command, word by word.
class CommandLine
{
public:
    CommandLine(const Document& document, const QString& command);
    //! A bare word (a subcommand, an option name).
    CommandLine& word(const QString& text);
    //! The entity's file, quoted. An entity in no file of its own (a derived
    //! cloud, one scan of a multi-scan E57), or changed since it was read (a
    //! computed field), is named NAME.ply and listed: the command then runs
    //! once the user has exported it so.
    CommandLine& file(const Document::Item& item);
    //! A file beside `item`'s own (its folder, else the current one), named
    //! after it: STEM + suffix + extension ("_c2c", ".ply").
    CommandLine& outputBeside(const QString& option, const Document::Item& item, const QString& suffix,
                              const QString& extension = ".ply");
    //! The options of `values` by their declarations: a switch as a flag when
    //! on (--no-NAME when off and on by default), a repeated text (joined by
    //! ';') as one option per value, a text of several values (--range A B)
    //! as its values, every value quoted.
    CommandLine& options(const std::map<std::string, std::string>& values, const std::vector<ParameterSpec>& specs);
    //! The command, with "  # export A.ply first" when an entity is in no file.
    QString text() const;

private:
    const Document& document_;
    QStringList words_;
    QStringList toExport_;
};

} // namespace scandiff::gui
