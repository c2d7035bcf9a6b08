// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The one error policy of scandiff.
//!
//! - Every public function of octree/, core/, io/ and plugins/ reports failure by
//!   throwing scandiff::Error. No integer status codes, no silent `false`.
//! - The message says *what* went wrong and *where*: the file name, line or byte
//!   offset, field or parameter name. It is written for the user, in one sentence,
//!   and front ends show it as it is (the CLI prints "error: <message>" and exits
//!   with the code below; the GUI shows it in a message box and the console).
//! - The code classifies the failure so front ends and tests can react without
//!   parsing text.
//! - Cancellation (the user pressed Cancel) is an Error with code Cancelled. An
//!   operation that throws, cancelled or not, leaves its inputs untouched: results
//!   are built in new buffers and only committed at the end.
//! - Warnings that do not stop an operation (e.g. "12 points with NaN coordinates
//!   were skipped") go to the log sink (Log.h), never to stdout directly.
//! - Bugs (broken invariants) are Internal; they are still reported, never abort().

#include <stdexcept>
#include <string>

namespace scandiff {

enum class ErrorCode {
    InvalidArgument = 2, //!< a parameter out of its range, an unknown option
    InvalidData = 3,     //!< malformed or inconsistent input data (file content, NaN coordinates, empty cloud)
    Io = 4,              //!< the file system: missing file, permission, disk full
    Unsupported = 5,     //!< a valid input this build does not handle (e.g. LAZ)
    Cancelled = 6,       //!< the user cancelled the operation
    Internal = 7         //!< a broken invariant: a bug of scandiff
};

class Error : public std::runtime_error
{
public:
    Error(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
    ErrorCode code() const noexcept { return code_; }
    //! The process exit status front ends use for this error.
    int exitStatus() const noexcept { return static_cast<int>(code_); }

private:
    ErrorCode code_;
};

//! Short name of a code, for logs and JSON ("invalid-data", ...).
const char* errorCodeName(ErrorCode code) noexcept;

} // namespace scandiff
