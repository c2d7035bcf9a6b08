// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/io/AtomicFile.h>

#include "TestSupport.h"

using namespace scandiff;
namespace fs = std::filesystem;

TEST(AtomicFile, CommitReplacesTheDestination)
{
    const fs::path dir = test::tempDir();
    const fs::path target = dir / "out.txt";
    test::writeText(target, "old content");
    {
        io::AtomicFile file(target);
        file.stream() << "new content";
        // Until commit, readers still see the old file.
        EXPECT_EQ(test::readBytes(target), "old content");
        file.commit();
    }
    EXPECT_EQ(test::readBytes(target), "new content");
    EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(AtomicFile, AnAbandonedWriteLeavesTheOldFileAndNoTemporary)
{
    const fs::path dir = test::tempDir();
    const fs::path target = dir / "out.txt";
    test::writeText(target, "precious");
    try {
        io::AtomicFile file(target);
        file.stream() << "half of a file";
        throw Error(ErrorCode::Cancelled, "cancelled");
    } catch (const Error&) {
    }
    EXPECT_EQ(test::readBytes(target), "precious");
    EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(AtomicFile, MissingFolderIsAClearError)
{
    try {
        io::AtomicFile file(test::tempDir() / "no" / "such" / "folder" / "out.ply");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::Io);
        EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos);
    }
}
