// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/io/FileIO.h>

#include "BuiltinFormats.h"
#include "TestSupport.h"

#include <csignal>
#include <sys/resource.h>

using namespace scandiff;

namespace {

ErrorCode readError(const io::FormatRegistry& registry, const std::filesystem::path& path, std::string* message = nullptr)
{
    try {
        io::readFile(registry, path);
    } catch (const Error& e) {
        if (message)
            *message = e.what();
        return e.code();
    }
    return ErrorCode::Internal;
}

} // namespace

TEST(FileIO, ExtensionsAreCaseInsensitive)
{
    const auto registry = test::builtinFormats();
    EXPECT_EQ(registry.forPath("scan.PLY").name, registry.forPath("scan.ply").name);
    EXPECT_EQ(io::lowerExtension("a/b/C.LaS"), "las");
}

TEST(FileIO, UnknownExtensionIsUnsupportedAndBrokenLazAndE57Invalid)
{
    const auto registry = test::builtinFormats();
    const auto dir = test::tempDir();
    test::writeText(dir / "scan.fls", "x");
    test::writeText(dir / "scan.e57", "x");
    test::writeText(dir / "scan.laz", "LASF");
    std::string message;
    EXPECT_EQ(readError(registry, dir / "scan.fls", &message), ErrorCode::Unsupported);
    EXPECT_NE(message.find("scan.fls"), std::string::npos);
    EXPECT_EQ(readError(registry, dir / "scan.e57", &message), ErrorCode::InvalidData);
    EXPECT_NE(message.find("not an E57 file"), std::string::npos) << message;
    EXPECT_EQ(readError(registry, dir / "scan.laz", &message), ErrorCode::InvalidData);
    EXPECT_NE(message.find("LAS header too short"), std::string::npos);
}

TEST(FileIO, MissingAndEmptyFilesNameTheFile)
{
    const auto registry = test::builtinFormats();
    const auto dir = test::tempDir();
    std::string message;
    for (const char* name : {"missing.ply", "missing.las", "missing.xyz", "missing.obj"}) {
        EXPECT_EQ(readError(registry, dir / name, &message), ErrorCode::Io) << name;
        EXPECT_NE(message.find(name), std::string::npos) << message;
    }
    for (const char* name : {"empty.ply", "empty.las", "empty.xyz", "empty.obj", "empty.stl", "empty.off"}) {
        test::writeText(dir / name, "");
        const ErrorCode code = readError(registry, dir / name, &message);
        EXPECT_EQ(code, ErrorCode::InvalidData) << name << ": " << message;
        EXPECT_NE(message.find(name), std::string::npos) << message;
    }
}

TEST(FileIO, WritingAPointCloudToAMeshOnlyFormatIsRefused)
{
    const auto registry = test::builtinFormats();
    PointCloud cloud;
    cloud.resize(2);
    EXPECT_THROW(io::writePointCloud(registry, cloud, test::tempDir() / "cloud.obj"), Error);
}

TEST(FileIO, EveryBuiltinFormatIsRegistered)
{
    const auto registry = test::builtinFormats();
    for (const char* ext : {"ply", "xyz", "txt", "csv", "pts", "asc", "las", "laz", "obj", "stl", "off", "dxf"})
        EXPECT_NO_THROW(registry.forPath(std::string("a.") + ext)) << ext;
}

namespace {

//! Files larger than `bytes` cannot be written while it lives: the kernel
//! answers EFBIG, as a full disk answers ENOSPC (SIGXFSZ, which would stop the
//! process, is ignored meanwhile). A full disk without a small partition.
class FileSizeLimit
{
public:
    explicit FileSizeLimit(rlim_t bytes)
    {
        ::getrlimit(RLIMIT_FSIZE, &saved_);
        previousHandler_ = std::signal(SIGXFSZ, SIG_IGN);
        rlimit limit = saved_;
        limit.rlim_cur = bytes;
        ::setrlimit(RLIMIT_FSIZE, &limit);
    }
    ~FileSizeLimit()
    {
        ::setrlimit(RLIMIT_FSIZE, &saved_);
        std::signal(SIGXFSZ, previousHandler_);
    }

private:
    rlimit saved_{};
    void (*previousHandler_)(int) = nullptr;
};

} // namespace

TEST(FileIO, AFullDiskLeavesTheExistingFileIntactAndNoTemporary)
{
    // Every writable format, writing over a file the user already has: the
    // write fails with Error(Io), the old file is untouched, nothing is left.
    io::FormatRegistry registry;
    io::registerBuiltinFormats(registry);
    PointCloud cloud;
    cloud.resize(20000);
    for (std::size_t i = 0; i < cloud.size(); ++i)
        cloud.positions()[i] = Eigen::Vector3f(static_cast<float>(i % 200), static_cast<float>(i / 200), 0.5f);
    cloud.addField("value");
    Mesh mesh;
    mesh.vertices = cloud.clone();
    for (std::uint32_t i = 0; i + 201 < 20000; ++i)
        mesh.triangles.push_back({i, i + 1, i + 200});
    const auto dir = test::tempDir();
    for (const char* name : {"out.ply", "out.xyz", "out.las", "out.pcd", "out.obj", "out.off", "out.stl"}) {
        const auto path = dir / name;
        test::writeText(path, "precious");
        const bool meshFormat = std::string(name).find(".obj") != std::string::npos ||
                                std::string(name).find(".off") != std::string::npos ||
                                std::string(name).find(".stl") != std::string::npos;
        ErrorCode code;
        {
            const FileSizeLimit full(64 * 1024);
            code = test::errorCodeOf([&] {
                if (meshFormat)
                    io::writeMesh(registry, mesh, path);
                else
                    io::writePointCloud(registry, cloud, path);
            });
        }
        EXPECT_EQ(code, ErrorCode::Io) << name;
        EXPECT_EQ(test::readBytes(path), "precious") << name;
        std::size_t files = 0;
        for (const auto& entry : std::filesystem::directory_iterator(dir))
            files += entry.path().filename().string().find(".tmp-") != std::string::npos;
        EXPECT_EQ(files, 0u) << name << ": a temporary file was left";
    }
}
