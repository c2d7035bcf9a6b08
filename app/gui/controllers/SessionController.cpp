// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/SessionController.h"

#include "TaskRunner.h"
#include "tools/MeasurePanel.h"
#include "panels/ScalarFieldPanel.h"
#include "view/CloudView.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/AtomicFile.h>
#include <scandiff/io/DxfReader.h>
#include <scandiff/io/DxfWriter.h>
#include <scandiff/io/FileIO.h>

#include <nlohmann/json.hpp>

#include <QFileDialog>
#include <QFileInfo>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>

namespace scandiff::gui {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr int kSessionVersion = 1;

// JSON has no infinity: an open threshold bound is written as null.
json bound(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
double bound(const json& j, double open) { return j.is_null() ? open : j.get<double>(); }

json cameraJson(const CameraState& c)
{
    return {{"position", c.position}, {"focalPoint", c.focalPoint}, {"viewUp", c.viewUp},
            {"viewAngle", c.viewAngle}, {"parallel", c.parallel}, {"parallelScale", c.parallelScale}};
}

//! What a PLY file does not hold: the sensor poses and the transformation history.
json provenanceJson(const PointCloud& points)
{
    json sensors = json::array();
    for (const SensorPose& s : points.sensors())
        sensors.push_back({{"position", {s.position.x(), s.position.y(), s.position.z()}},
                           {"orientation", {s.orientation.w(), s.orientation.x(), s.orientation.y(), s.orientation.z()}},
                           {"steps", {s.yawStep, s.pitchStep}},
                           {"fieldOfView", {s.yawMin, s.yawMax, s.pitchMin, s.pitchMax}},
                           {"maxRange", bound(s.maxRange)}});
    json transforms = json::array();
    for (const AppliedTransform& t : points.transformHistory()) {
        json matrix = json::array();
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c)
                matrix.push_back(t.matrix(r, c));
        transforms.push_back({{"description", t.description}, {"matrix", matrix}});
    }
    return {{"sensors", sensors}, {"transforms", transforms}};
}

void restoreProvenance(const json& e, PointCloud& points)
{
    for (const json& s : e.value("sensors", json::array())) {
        SensorPose pose;
        const auto p = s.at("position").get<std::vector<double>>();
        const auto q = s.at("orientation").get<std::vector<double>>();
        const auto steps = s.at("steps").get<std::vector<double>>();
        const auto fov = s.at("fieldOfView").get<std::vector<double>>();
        if (p.size() != 3 || q.size() != 4 || steps.size() != 2 || fov.size() != 4)
            throw Error(ErrorCode::InvalidData, "a sensor pose of the session is malformed");
        pose.position = Eigen::Vector3d(p[0], p[1], p[2]);
        pose.orientation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
        pose.yawStep = steps[0];
        pose.pitchStep = steps[1];
        pose.yawMin = fov[0];
        pose.yawMax = fov[1];
        pose.pitchMin = fov[2];
        pose.pitchMax = fov[3];
        pose.maxRange = bound(s.at("maxRange"), std::numeric_limits<double>::infinity());
        points.sensors().push_back(pose);
    }
    for (const json& t : e.value("transforms", json::array())) {
        const auto values = t.at("matrix").get<std::vector<double>>();
        if (values.size() != 16)
            throw Error(ErrorCode::InvalidData, "a transformation of the session is not 16 numbers");
        AppliedTransform step;
        step.description = t.value("description", std::string());
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c)
                step.matrix(r, c) = values[static_cast<std::size_t>(4 * r + c)];
        points.transformHistory().push_back(step);
    }
}

CameraState cameraFrom(const json& j)
{
    CameraState c;
    c.position = j.at("position").get<std::array<double, 3>>();
    c.focalPoint = j.at("focalPoint").get<std::array<double, 3>>();
    c.viewUp = j.at("viewUp").get<std::array<double, 3>>();
    c.viewAngle = j.at("viewAngle").get<double>();
    c.parallel = j.at("parallel").get<bool>();
    c.parallelScale = j.at("parallelScale").get<double>();
    return c;
}

fs::path dataFolder(const fs::path& session) { return session.parent_path() / (session.filename().string() + ".data"); }

} // namespace

SessionController::SessionController(const PluginRegistry& registry, Document& document, CloudView& view,
                                     ScalarFieldPanel& scalarPanel, QWidget* parentWindow)
    : QObject(parentWindow), registry_(registry), document_(document), view_(view), scalarPanel_(scalarPanel),
      parentWindow_(parentWindow)
{
}

bool SessionController::save(const QString& qpath)
{
    const fs::path path = qpath.toStdString();
    const fs::path data = dataFolder(path);
    // The description is made here, on the GUI thread; the worker only writes files.
    json entities = json::array();
    std::vector<std::pair<const io::Entity*, std::string>> files;
    std::vector<std::pair<std::shared_ptr<const Drawing>, std::string>> drawings; // as DXF
    for (EntityId id : document_.ids()) {
        const Document::Item& item = document_.item(id);
        const std::string file = item.isGroup() ? std::string() : "entity_" + std::to_string(id) + (item.isDrawing() ? ".dxf" : ".ply");
        if (item.isDrawing())
            drawings.emplace_back(item.drawing, file);
        else if (!item.isGroup())
            files.emplace_back(&item.entity, file);
        json fields = json::object();
        for (const auto& [name, display] : item.display.fields)
            fields[name] = {{"scale", display.scale.toText()},          {"low", bound(display.low)},
                            {"high", bound(display.high)},               {"colourLow", bound(display.colourLow)},
                            {"colourHigh", bound(display.colourHigh)}, {"symmetric", display.symmetric}};
        json properties = json::array();
        for (const auto& [key, value] : item.properties)
            properties.push_back({key.toStdString(), value.toStdString()});
        entities.push_back({{"id", id},
                            {"name", item.name.toStdString()},
                            {"parent", item.parent},
                            {"data", file.empty() ? std::string() : data.filename().string() + "/" + file},
                            {"source", item.sourcePath.toStdString()},
                            {"visible", item.display.visible},
                            {"activeField", item.display.activeField},
                            {"neutral", item.display.neutral},
                            {"blendColours", item.display.blendColours},
                            {"pointSize", item.display.pointSize},
                            {"outside", item.display.outside == FieldColouring::Outside::Grey ? "grey" : "hide"},
                            {"fields", fields},
                            {"kind", item.isGroup() ? "group" : item.isDrawing() ? "drawing" : "data"},
                            {"properties", properties},
                            {"provenance", provenanceJson(item.points())}});
    }
    json scales = json::array();
    for (const ColourScale& s : scalarPanel_.customScales())
        scales.push_back(s.toText());
    json measurements = json::array(), measurementNotes = json::array();
    if (measure_)
        for (std::size_t k = 0; k < measure_->measurements().size(); ++k)
            if (const auto& points = measure_->measurements()[k]; !points.empty()) {
                json list = json::array();
                for (const Eigen::Vector3d& p : points)
                    list.push_back({p.x(), p.y(), p.z()});
                measurements.push_back(list);
                measurementNotes.push_back(measure_->notes()[k].toStdString());
            }
    const json session = {{"scandiffSession", kSessionVersion},
                          {"entities", entities},
                          {"customScales", scales},
                          {"camera", cameraJson(view_.camera())},
                          {"pointSize", view_.pointSize()},
                          {"measurements", measurements},
                          {"measurementNotes", measurementNotes}};

    const TaskResult result = runTask(parentWindow_, tr("Saving session"), [&](ProgressObserver& progress) {
        // A previous save stays whole until the new one is: its data folder is
        // replaced only once every file of the new one is written.
        const fs::path fresh = data.parent_path() / (data.filename().string() + ".new");
        const fs::path previous = data.parent_path() / (data.filename().string() + ".old");
        std::error_code ec;
        fs::remove_all(fresh, ec);
        fs::create_directories(fresh);
        io::WriteOptions options;
        options.progress = &progress;
        for (const auto& [entity, file] : files)
            io::writeFile(registry_.formats, *entity, fresh / file, options);
        for (const auto& [drawing, file] : drawings)
            io::writeDrawingDxf(*drawing, fresh / file);
        fs::remove_all(previous, ec);
        if (fs::exists(data))
            fs::rename(data, previous);
        fs::rename(fresh, data);
        io::AtomicFile out(path);
        out.stream() << session.dump(2) << '\n';
        out.commit();
        fs::remove_all(previous, ec);
    });
    if (result.outcome != TaskOutcome::Done) {
        if (result.outcome == TaskOutcome::Cancelled)
            emit cancelled(tr("Saving the session was cancelled; the previous one is unchanged"));
        else
            emit failed(tr("Saving the session failed: %1").arg(result.error));
        return false;
    }
    document_.markAllSaved();
    emit finished(tr("saved session %1 (%2 entities)").arg(qpath).arg(document_.size()));
    return true;
}

bool SessionController::restore(const QString& qpath)
{
    const fs::path path = qpath.toStdString();
    // Everything is read and checked by the worker before the document changes:
    // a bad session leaves the current work as it was.
    struct Entry
    {
        int id = kNoEntity, parent = kNoEntity;
        QString name, source;
        bool visible = true;
        std::string activeField;
        bool neutral = false;
        bool blendColours = false;
        float pointSize = 0;
        FieldColouring::Outside outside = FieldColouring::Outside::Hide;
        std::map<std::string, FieldDisplay> fields;
        io::Entity entity;
        std::optional<Drawing> drawing;
        bool group = false;
        Document::Properties properties;
    };
    std::vector<Entry> entries;
    std::vector<ColourScale> scales;
    std::optional<CameraState> camera;
    float pointSize = 2.0f;
    std::vector<std::vector<Eigen::Vector3d>> measurements;
    std::vector<QString> notes;
    const TaskResult result = runTask(parentWindow_, tr("Opening session"), [&](ProgressObserver& progress) {
        std::ifstream in(path);
        if (!in)
            throw Error(ErrorCode::Io, "cannot read " + path.string());
        try {
            const json session = json::parse(in);
            if (!session.contains("scandiffSession") || session.at("scandiffSession").get<int>() > kSessionVersion)
                throw Error(ErrorCode::InvalidData, path.string() + " is not a scandiff session this version reads");
            io::ReadOptions options;
            options.progress = &progress;
            for (const json& e : session.at("entities")) {
                Entry entry;
                entry.id = e.at("id").get<int>();
                entry.parent = e.value("parent", int(kNoEntity));
                entry.name = QString::fromStdString(e.at("name").get<std::string>());
                entry.source = QString::fromStdString(e.value("source", std::string()));
                entry.visible = e.value("visible", true);
                entry.activeField = e.value("activeField", std::string());
                entry.neutral = e.value("neutral", false);
                entry.blendColours = e.value("blendColours", false);
                entry.pointSize = e.value("pointSize", 0.0f);
                entry.outside = e.value("outside", std::string("hide")) == "grey" ? FieldColouring::Outside::Grey
                                                                                  : FieldColouring::Outside::Hide;
                for (const json& row : e.value("properties", json::array()))
                    entry.properties.emplace_back(QString::fromStdString(row.at(0).get<std::string>()),
                                                  QString::fromStdString(row.at(1).get<std::string>()));
                const json fields = e.value("fields", json::object()); // items() must not outlive it
                for (const auto& [name, f] : fields.items()) {
                    FieldDisplay display;
                    if (const auto scale = ColourScale::fromText(f.at("scale").get<std::string>()))
                        display.scale = *scale;
                    display.low = bound(f.at("low"), -std::numeric_limits<double>::infinity());
                    display.high = bound(f.at("high"), std::numeric_limits<double>::infinity());
                    // Sessions written before the colour range had none: automatic.
                    display.colourLow = bound(f.value("colourLow", json(nullptr)), -std::numeric_limits<double>::infinity());
                    display.colourHigh = bound(f.value("colourHigh", json(nullptr)), std::numeric_limits<double>::infinity());
                    display.symmetric = f.value("symmetric", false);
                    entry.fields[name] = display;
                }
                if (e.value("kind", std::string("data")) == "group") {
                    entry.group = true;
                    entries.push_back(std::move(entry));
                    continue;
                }
                if (e.value("kind", std::string("data")) == "drawing") {
                    entry.drawing = io::readDrawingDxf(path.parent_path() / e.at("data").get<std::string>(), &progress);
                    entries.push_back(std::move(entry));
                    continue;
                }
                entry.entity = io::readFile(registry_.formats, path.parent_path() / e.at("data").get<std::string>(), options);
                if (e.contains("provenance")) {
                    PointCloud& points = pointsOf(entry.entity);
                    points.sensors().clear(); // the session's list is the whole list
                    restoreProvenance(e.at("provenance"), points);
                }
                entries.push_back(std::move(entry));
            }
            const json scaleTexts = session.value("customScales", json::array());
            for (const json& text : scaleTexts)
                if (const auto scale = ColourScale::fromText(text.get<std::string>()))
                    scales.push_back(*scale);
            if (session.contains("camera"))
                camera = cameraFrom(session.at("camera"));
            pointSize = session.value("pointSize", 2.0f);
            for (const json& list : session.value("measurements", json::array())) {
                std::vector<Eigen::Vector3d> points;
                for (const json& p : list)
                    points.emplace_back(p.at(0).get<double>(), p.at(1).get<double>(), p.at(2).get<double>());
                measurements.push_back(std::move(points));
            }
            for (const json& note : session.value("measurementNotes", json::array()))
                notes.push_back(QString::fromStdString(note.get<std::string>()));
        } catch (const json::exception& e) {
            throw Error(ErrorCode::InvalidData, path.string() + " is not a valid scandiff session: " + e.what());
        }
    });
    if (result.outcome != TaskOutcome::Done) {
        if (result.outcome == TaskOutcome::Cancelled)
            emit cancelled(tr("Opening the session was cancelled"));
        else
            emit failed(tr("Opening the session failed: %1").arg(result.error));
        return false;
    }
    document_.clear();
    for (const ColourScale& scale : scales)
        scalarPanel_.addCustomScale(scale);
    std::map<int, EntityId> newIds;
    for (Entry& e : entries) {
        const auto parent = newIds.find(e.parent);
        const EntityId parentId = parent == newIds.end() ? kNoEntity : parent->second;
        const EntityId id = e.group     ? document_.addGroup(e.name, parentId, e.source)
                            : e.drawing ? document_.addDrawing(e.name, std::move(*e.drawing), parentId, e.source)
                                        : document_.add(e.name, std::move(e.entity), parentId, e.source, std::move(e.properties));
        newIds[e.id] = id;
        for (const auto& [name, display] : e.fields)
            document_.setFieldDisplay(id, name, display);
        document_.setActiveField(id, e.activeField);
        document_.setNeutral(id, e.neutral);
        document_.setBlendColours(id, e.blendColours);
        document_.setPointSize(id, e.pointSize);
        document_.setOutsideMode(id, e.outside);
        document_.setVisible(id, e.visible);
    }
    view_.setPointSize(pointSize);
    // The measurements first: the camera's near and far planes take them in.
    if (measure_)
        measure_->setMeasurements(std::move(measurements), std::move(notes));
    if (camera)
        view_.setCamera(*camera);
    document_.markAllSaved(); // derived entities are in the session's data folder
    emit finished(tr("opened session %1 (%2 entities)").arg(qpath).arg(document_.size()));
    return true;
}

bool SessionController::saveWithDialog()
{
    const QString path = QFileDialog::getSaveFileName(parentWindow_, tr("Save session"), "session.scandiff", tr("scandiff session (*.scandiff)"));
    return !path.isEmpty() && save(path);
}

void SessionController::restoreWithDialog()
{
    if (mayDiscard_ && !mayDiscard_())
        return;
    const QString path = QFileDialog::getOpenFileName(parentWindow_, tr("Open session"), QString(), tr("scandiff session (*.scandiff)"));
    if (!path.isEmpty())
        restore(path);
}

} // namespace scandiff::gui
