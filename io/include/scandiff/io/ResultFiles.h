// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Files of tool results that are not clouds or meshes: tables as CSV and
//! transformations as 4 x 4 text matrices (CloudCompare's layout: four lines
//! of four numbers, so matrices go back and forth between the two programs).
//! Written through AtomicFile like every other output.

#include <scandiff/core/Table.h>

#include <Eigen/Core>

#include <filesystem>
#include <string>

namespace scandiff::io {

//! Table::toText() (CSV, or plain numbers) into `path`. Throws Error(Io).
void writeTable(const Table& table, const std::filesystem::path& path);

//! Four lines of four numbers, each the shortest text that reads back to the
//! same double. Throws Error(Io).
void writeMatrix(const Eigen::Matrix4d& matrix, const std::filesystem::path& path);
//! The same text, for the console and the log.
std::string matrixText(const Eigen::Matrix4d& matrix);

} // namespace scandiff::io
