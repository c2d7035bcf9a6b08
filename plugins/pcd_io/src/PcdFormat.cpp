// SPDX-License-Identifier: GPL-3.0-or-later
//! PCD (Point Cloud Library) files, read and written with PCL's own io, which
//! knows every PCD variant, including the LZF binary_compressed one.
//!
//! Mapping: x y z -> positions (float or double fields), rgb/rgba (packed) ->
//! colours, normal_x/y/z -> normals, every other field -> a scalar field (a
//! field with count c > 1 becomes name_0 .. name_{c-1}). The VIEWPOINT becomes a
//! sensor pose when it is not the default one or the cloud is organised (a
//! depth-camera frame, whose viewpoint is the camera). Organised clouds mark
//! missing returns with NaN: those points are dropped, as for every reader.
//! Writing: float x y z, or double when the cloud has a non-zero origin so that
//! georeferenced coordinates keep their precision.

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/AtomicFile.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <cstring>

namespace {

namespace fs = std::filesystem;
using namespace scandiff;

double fieldValue(const std::uint8_t* p, std::uint8_t datatype, bool bigEndian)
{
    std::uint8_t bytes[8];
    const std::size_t size = pcl::getFieldSize(datatype);
    std::memcpy(bytes, p, size);
    if (bigEndian)
        std::reverse(bytes, bytes + size);
    switch (datatype) {
    case pcl::PCLPointField::INT8: { std::int8_t v; std::memcpy(&v, bytes, 1); return v; }
    case pcl::PCLPointField::UINT8: return bytes[0];
    case pcl::PCLPointField::INT16: { std::int16_t v; std::memcpy(&v, bytes, 2); return v; }
    case pcl::PCLPointField::UINT16: { std::uint16_t v; std::memcpy(&v, bytes, 2); return v; }
    case pcl::PCLPointField::INT32: { std::int32_t v; std::memcpy(&v, bytes, 4); return v; }
    case pcl::PCLPointField::UINT32: { std::uint32_t v; std::memcpy(&v, bytes, 4); return v; }
    case pcl::PCLPointField::FLOAT32: { float v; std::memcpy(&v, bytes, 4); return v; }
    case pcl::PCLPointField::FLOAT64: { double v; std::memcpy(&v, bytes, 8); return v; }
    default: return std::nan("");
    }
}

//! PCL's reader trusts the header: an empty file or one without FIELDS makes it
//! crash (PCL 1.13). So the header is checked here first, and the data size
//! against it, before PCL sees the file.
void checkPcdHeader(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw Error(ErrorCode::Io, path.string() + ": cannot open");
    in.seekg(0, std::ios::end);
    const auto fileSize = static_cast<std::uint64_t>(in.tellg());
    in.seekg(0);
    auto fail = [&](const std::string& why) { throw Error(ErrorCode::InvalidData, path.string() + ": not a valid PCD file: " + why); };
    if (fileSize == 0)
        fail("the file is empty");
    std::vector<std::string> fields;
    std::vector<std::uint64_t> sizes, counts;
    std::uint64_t width = 0, height = 0, points = 0;
    bool haveWidth = false, haveHeight = false, havePoints = false;
    std::string data;
    std::string line;
    int lineNumber = 0;
    while (data.empty() && std::getline(in, line)) {
        ++lineNumber;
        if (lineNumber > 64)
            fail("no DATA line in the first 64 lines");
        if (!line.empty() && line.back() == '\r')
            line.pop_back();
        if (line.empty() || line[0] == '#')
            continue;
        std::istringstream words(line);
        std::string key;
        words >> key;
        auto numbers = [&](std::vector<std::uint64_t>& into) {
            std::string w;
            while (words >> w) {
                try {
                    into.push_back(std::stoull(w));
                } catch (const std::exception&) {
                    fail("line " + std::to_string(lineNumber) + ": '" + w + "' is not a number");
                }
            }
        };
        auto one = [&](std::uint64_t& into, bool& flag) {
            std::vector<std::uint64_t> v;
            numbers(v);
            if (v.size() != 1)
                fail("line " + std::to_string(lineNumber) + ": " + key + " needs one number");
            into = v[0];
            flag = true;
        };
        if (key == "VERSION" || key == "VIEWPOINT" || key == "TYPE")
            continue;
        if (key == "FIELDS") {
            std::string w;
            while (words >> w)
                fields.push_back(w);
        } else if (key == "SIZE")
            numbers(sizes);
        else if (key == "COUNT")
            numbers(counts);
        else if (key == "WIDTH")
            one(width, haveWidth);
        else if (key == "HEIGHT")
            one(height, haveHeight);
        else if (key == "POINTS")
            one(points, havePoints);
        else if (key == "DATA")
            words >> data;
        else
            fail("line " + std::to_string(lineNumber) + ": unknown header keyword '" + key.substr(0, 32) + "'");
    }
    if (data.empty())
        fail("the header has no DATA line");
    if (fields.empty() || sizes.size() != fields.size() || (!counts.empty() && counts.size() != fields.size()))
        fail("FIELDS, SIZE and COUNT do not describe the same fields");
    if (!haveWidth || !haveHeight || !havePoints || width * height != points)
        fail("WIDTH x HEIGHT must equal POINTS");
    std::uint64_t pointStep = 0;
    for (std::size_t f = 0; f < fields.size(); ++f) {
        if (sizes[f] != 1 && sizes[f] != 2 && sizes[f] != 4 && sizes[f] != 8)
            fail("field '" + fields[f] + "' has size " + std::to_string(sizes[f]));
        pointStep += sizes[f] * (counts.empty() ? 1 : counts[f]);
    }
    const auto headerEnd = static_cast<std::uint64_t>(in.tellg());
    const std::uint64_t remaining = fileSize >= headerEnd ? fileSize - headerEnd : 0;
    if (data == "binary") {
        if (remaining < points * pointStep)
            fail("truncated: " + std::to_string(points) + " points need " + std::to_string(points * pointStep) +
                 " bytes of data, the file has " + std::to_string(remaining));
    } else if (data == "binary_compressed") {
        std::uint32_t sizesOfBlock[2] = {0, 0};
        if (remaining < 8 || !in.read(reinterpret_cast<char*>(sizesOfBlock), 8))
            fail("truncated compressed data");
        if (sizesOfBlock[0] > remaining - 8)
            fail("truncated: the compressed block is " + std::to_string(sizesOfBlock[0]) + " bytes, the file has " +
                 std::to_string(remaining - 8));
        if (sizesOfBlock[1] != points * pointStep)
            fail("the uncompressed size disagrees with POINTS");
    } else if (data != "ascii") {
        fail("unknown DATA encoding '" + data.substr(0, 32) + "'");
    }
}

io::Entity readPcd(const fs::path& path, const io::ReadOptions& options)
{
    checkPcdHeader(path);
    ProgressTicker ticker(options.progress, "Reading " + path.filename().string(), 2);
    pcl::PCLPointCloud2 blob;
    Eigen::Vector4f viewOrigin;
    Eigen::Quaternionf viewOrientation;
    int version = 0;
    pcl::PCDReader reader;
    // PCL prints its own errors on stderr; we report one clear message instead.
    const auto verbosity = pcl::console::getVerbosityLevel();
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
    int status = -1;
    try {
        status = reader.read(path.string(), blob, viewOrigin, viewOrientation, version);
    } catch (const std::exception& e) {
        pcl::console::setVerbosityLevel(verbosity);
        throw Error(ErrorCode::InvalidData, path.string() + ": not a valid PCD file (" + e.what() + ")");
    }
    pcl::console::setVerbosityLevel(verbosity);
    if (status < 0)
        throw Error(ErrorCode::InvalidData, path.string() + ": not a valid PCD file (bad header, or the data is truncated or corrupt)");
    ticker.step();

    const std::size_t n = static_cast<std::size_t>(blob.width) * blob.height;
    if (blob.data.size() < n * blob.point_step)
        throw Error(ErrorCode::InvalidData, path.string() + ": truncated: " + std::to_string(n) + " points announced, data for fewer");
    const pcl::PCLPointField* axes[3] = {nullptr, nullptr, nullptr};
    const pcl::PCLPointField* normalAxes[3] = {nullptr, nullptr, nullptr};
    const pcl::PCLPointField* colour = nullptr;
    std::vector<const pcl::PCLPointField*> others;
    for (const auto& f : blob.fields) {
        if (f.name == "x") axes[0] = &f;
        else if (f.name == "y") axes[1] = &f;
        else if (f.name == "z") axes[2] = &f;
        else if (f.name == "normal_x") normalAxes[0] = &f;
        else if (f.name == "normal_y") normalAxes[1] = &f;
        else if (f.name == "normal_z") normalAxes[2] = &f;
        else if ((f.name == "rgb" || f.name == "rgba") && pcl::getFieldSize(f.datatype) == 4) colour = &f;
        else if (f.name != "_") others.push_back(&f);
    }
    if (!axes[0] || !axes[1] || !axes[2])
        throw Error(ErrorCode::InvalidData, path.string() + ": the PCD file has no x, y and z fields");

    const bool bigEndian = blob.is_bigendian;
    std::vector<Eigen::Vector3d> global(n);
    BoundingBox box;
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint8_t* record = blob.data.data() + i * blob.point_step;
        for (int a = 0; a < 3; ++a)
            global[i][a] = fieldValue(record + axes[a]->offset, axes[a]->datatype, bigEndian);
        if (global[i].allFinite()) {
            box.min = box.empty ? global[i] : box.min.cwiseMin(global[i]);
            box.max = box.empty ? global[i] : box.max.cwiseMax(global[i]);
            box.empty = false;
        }
    }
    PointCloud cloud;
    const Eigen::Vector3d origin = options.origin ? *options.origin : suggestOrigin(box);
    cloud.setOrigin(origin);
    cloud.resize(n);
    for (std::size_t i = 0; i < n; ++i)
        cloud.positions()[i] = (global[i] - origin).cast<float>();
    global.clear();
    global.shrink_to_fit();
    if (normalAxes[0] && normalAxes[1] && normalAxes[2]) {
        auto& normals = cloud.enableNormals();
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint8_t* record = blob.data.data() + i * blob.point_step;
            for (int a = 0; a < 3; ++a)
                normals[i][a] = static_cast<float>(fieldValue(record + normalAxes[a]->offset, normalAxes[a]->datatype, bigEndian));
        }
    }
    if (colour) {
        auto& colours = cloud.enableColors();
        for (std::size_t i = 0; i < n; ++i) {
            // PCL packs colours as 0x00RRGGBB (rgb) or 0xAARRGGBB (rgba) in 4 bytes, whatever the declared type.
            std::uint32_t packed;
            std::memcpy(&packed, blob.data.data() + i * blob.point_step + colour->offset, 4);
            colours[i] = Rgb8{static_cast<std::uint8_t>(packed >> 16), static_cast<std::uint8_t>(packed >> 8),
                              static_cast<std::uint8_t>(packed)};
        }
    }
    for (const auto* f : others) {
        const std::size_t count = std::max<std::uint32_t>(f->count, 1);
        const std::size_t size = pcl::getFieldSize(f->datatype);
        for (std::size_t c = 0; c < count; ++c) {
            ScalarField& field = cloud.addField(count == 1 ? f->name : f->name + "_" + std::to_string(c));
            for (std::size_t i = 0; i < n; ++i)
                field.setValue(i, fieldValue(blob.data.data() + i * blob.point_step + f->offset + c * size, f->datatype, bigEndian));
        }
    }
    const bool defaultViewpoint = viewOrigin.head<3>().isZero() && viewOrientation.coeffs().isApprox(Eigen::Quaternionf::Identity().coeffs());
    if (!defaultViewpoint || blob.height > 1) {
        SensorPose pose;
        pose.position = viewOrigin.head<3>().cast<double>();
        pose.orientation = viewOrientation.cast<double>();
        cloud.sensors().push_back(pose);
    }
    const std::size_t dropped = cloud.removeNonFinitePoints();
    if (dropped > 0)
        logWarning(path.string() + ": " + std::to_string(dropped) + " points with non-finite coordinates were skipped");
    ticker.step();
    return cloud;
}

void writePcd(const PointCloud& cloud, const fs::path& path, const io::WriteOptions& options)
{
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), 2);
    pcl::PCLPointCloud2 blob;
    const bool doubles = !cloud.origin().isZero();
    std::uint32_t offset = 0;
    auto addField = [&](const std::string& name, std::uint8_t type) {
        pcl::PCLPointField f;
        f.name = name;
        f.offset = offset;
        f.datatype = type;
        f.count = 1;
        offset += pcl::getFieldSize(type);
        blob.fields.push_back(f);
    };
    const std::uint8_t coordinateType = doubles ? pcl::PCLPointField::FLOAT64 : pcl::PCLPointField::FLOAT32;
    addField("x", coordinateType);
    addField("y", coordinateType);
    addField("z", coordinateType);
    if (cloud.hasNormals()) {
        addField("normal_x", pcl::PCLPointField::FLOAT32);
        addField("normal_y", pcl::PCLPointField::FLOAT32);
        addField("normal_z", pcl::PCLPointField::FLOAT32);
    }
    if (cloud.hasColors())
        addField("rgb", pcl::PCLPointField::FLOAT32); // PCL's convention: packed bytes stored in a float
    for (const auto& f : cloud.fields())
        addField(f.name(), f.offset() != 0.0 ? pcl::PCLPointField::FLOAT64 : pcl::PCLPointField::FLOAT32);
    const std::size_t n = cloud.size();
    blob.width = static_cast<std::uint32_t>(n);
    blob.height = 1;
    blob.point_step = offset;
    blob.row_step = static_cast<std::uint32_t>(offset * n);
    blob.is_dense = true;
    blob.data.resize(static_cast<std::size_t>(offset) * n);
    for (std::size_t i = 0; i < n; ++i) {
        std::uint8_t* record = blob.data.data() + i * offset;
        std::size_t at = 0;
        const Eigen::Vector3d p = cloud.globalPosition(i);
        for (int a = 0; a < 3; ++a) {
            if (doubles) {
                std::memcpy(record + at, &p[a], 8);
                at += 8;
            } else {
                const float v = cloud.positions()[i][a];
                std::memcpy(record + at, &v, 4);
                at += 4;
            }
        }
        if (cloud.hasNormals()) {
            std::memcpy(record + at, cloud.normals()[i].data(), 12);
            at += 12;
        }
        if (cloud.hasColors()) {
            const Rgb8 c = cloud.colors()[i];
            const std::uint32_t packed = (std::uint32_t(c.r) << 16) | (std::uint32_t(c.g) << 8) | c.b;
            std::memcpy(record + at, &packed, 4);
            at += 4;
        }
        for (const auto& f : cloud.fields()) {
            if (f.offset() != 0.0) {
                const double v = f.value(i);
                std::memcpy(record + at, &v, 8);
                at += 8;
            } else {
                std::memcpy(record + at, &f.values()[i], 4);
                at += 4;
            }
        }
    }
    ticker.step();
    Eigen::Vector4f viewOrigin = Eigen::Vector4f::Zero();
    Eigen::Quaternionf viewOrientation = Eigen::Quaternionf::Identity();
    if (!cloud.sensors().empty()) {
        viewOrigin.head<3>() = cloud.sensors().front().position.cast<float>();
        viewOrientation = cloud.sensors().front().orientation.cast<float>();
    }
    io::AtomicFile file(path);
    pcl::PCDWriter writer;
    int status = 0;
    switch (options.encoding) {
    case io::Encoding::Ascii: status = writer.writeASCII(file.tempPath().string(), blob, viewOrigin, viewOrientation, 10); break;
    case io::Encoding::BinaryCompressed: status = writer.writeBinaryCompressed(file.tempPath().string(), blob, viewOrigin, viewOrientation); break;
    case io::Encoding::BinaryBigEndian:
        throw Error(ErrorCode::Unsupported, path.string() + ": PCD has no big-endian encoding");
    default: status = writer.writeBinary(file.tempPath().string(), blob, viewOrigin, viewOrientation); break;
    }
    if (status < 0)
        throw Error(ErrorCode::Io, path.string() + ": PCL could not write the file");
    file.commit();
    ticker.step();
}

} // namespace

void scandiff_register_plugin_pcd_io(scandiff::PluginRegistry& registry)
{
    registry.plugins.push_back({"pcd_io", "PCD files (ascii, binary, binary_compressed) through PCL's io", "PCL io"});
    scandiff::io::FormatHandler handler;
    handler.name = "PCD";
    handler.extensions = {"pcd"};
    handler.read = readPcd;
    handler.writeCloud = writePcd;
    registry.formats.add(std::move(handler));
}
