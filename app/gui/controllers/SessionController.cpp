// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/SessionController.h"

#include "TaskRunner.h"
#include "panels/ScalarFieldPanel.h"
#include "view/CloudView.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/AtomicFile.h>
#include <scandiff/io/FileIO.h>

#include <nlohmann/json.hpp>

#include <QFileDialog>
#include <QFileInfo>

#include <cmath>
#include <filesystem>
#include <fstream>

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
    const TaskResult result = runTask(parentWindow_, tr("Saving session"), [&](ProgressObserver&) {
        const fs::path data = dataFolder(path);
        fs::create_directories(data);
        json entities = json::array();
        for (EntityId id : document_.ids()) {
            const Document::Item& item = document_.item(id);
            const std::string file = "entity_" + std::to_string(id) + ".ply";
            io::writeFile(registry_.formats, item.entity, data / file);
            json fields = json::object();
            for (const auto& [name, display] : item.display.fields)
                fields[name] = {{"scale", display.scale.toText()}, {"low", bound(display.low)}, {"high", bound(display.high)}};
            entities.push_back({{"id", id},
                                {"name", item.name.toStdString()},
                                {"parent", item.parent},
                                {"data", data.filename().string() + "/" + file},
                                {"source", item.sourcePath.toStdString()},
                                {"visible", item.display.visible},
                                {"activeField", item.display.activeField},
                                {"outside", item.display.outside == FieldColouring::Outside::Grey ? "grey" : "hide"},
                                {"fields", fields}});
        }
        json scales = json::array();
        for (const ColourScale& s : scalarPanel_.customScales())
            scales.push_back(s.toText());
        const json session = {{"scandiffSession", kSessionVersion},
                              {"entities", entities},
                              {"customScales", scales},
                              {"camera", cameraJson(view_.camera())},
                              {"pointSize", view_.pointSize()}};
        io::AtomicFile out(path);
        out.stream() << session.dump(2) << '\n';
        out.commit();
    });
    if (result.outcome != TaskOutcome::Done) {
        emit failed(tr("Saving the session failed: %1").arg(result.error));
        return false;
    }
    emit finished(tr("saved session %1 (%2 entities)").arg(qpath).arg(document_.size()));
    return true;
}

bool SessionController::restore(const QString& qpath)
{
    const fs::path path = qpath.toStdString();
    json session;
    struct Loaded
    {
        json description;
        io::Entity entity;
    };
    std::vector<Loaded> loaded;
    const TaskResult result = runTask(parentWindow_, tr("Opening session"), [&](ProgressObserver& progress) {
        std::ifstream in(path);
        if (!in)
            throw Error(ErrorCode::Io, "cannot read " + path.string());
        try {
            session = json::parse(in);
        } catch (const json::exception& e) {
            throw Error(ErrorCode::InvalidData, path.string() + " is not a scandiff session: " + e.what());
        }
        if (!session.contains("scandiffSession") || session.at("scandiffSession").get<int>() > kSessionVersion)
            throw Error(ErrorCode::InvalidData, path.string() + " is not a scandiff session this version reads");
        io::ReadOptions options;
        options.progress = &progress;
        try {
            for (const json& e : session.at("entities"))
                loaded.push_back({e, io::readFile(registry_.formats, path.parent_path() / e.at("data").get<std::string>(), options)});
        } catch (const json::exception& e) {
            throw Error(ErrorCode::InvalidData, path.string() + ": malformed session entry: " + e.what());
        }
    });
    if (result.outcome != TaskOutcome::Done) {
        emit failed(tr("Opening the session failed: %1").arg(result.error));
        return false;
    }
    try {
        // Everything is read: only now is the current document replaced.
        document_.clear();
        for (const json& s : session.value("customScales", json::array()))
            if (const auto scale = ColourScale::fromText(s.get<std::string>()))
                scalarPanel_.addCustomScale(*scale);
        std::map<int, EntityId> newIds;
        for (Loaded& l : loaded) {
            const json& e = l.description;
            const auto parent = newIds.find(e.value("parent", int(kNoEntity)));
            const EntityId id = document_.add(QString::fromStdString(e.at("name").get<std::string>()), std::move(l.entity),
                                              parent == newIds.end() ? kNoEntity : parent->second,
                                              QString::fromStdString(e.value("source", std::string())));
            newIds[e.at("id").get<int>()] = id;
            for (const auto& [name, f] : e.value("fields", json::object()).items()) {
                FieldDisplay display;
                if (const auto scale = ColourScale::fromText(f.at("scale").get<std::string>()))
                    display.scale = *scale;
                display.low = bound(f.at("low"), -std::numeric_limits<double>::infinity());
                display.high = bound(f.at("high"), std::numeric_limits<double>::infinity());
                document_.setFieldDisplay(id, name, display);
            }
            document_.setActiveField(id, e.value("activeField", std::string()));
            document_.setOutsideMode(id, e.value("outside", std::string("hide")) == "grey" ? FieldColouring::Outside::Grey
                                                                                          : FieldColouring::Outside::Hide);
            document_.setVisible(id, e.value("visible", true));
        }
        view_.setPointSize(session.value("pointSize", 2.0f));
        if (session.contains("camera"))
            view_.setCamera(cameraFrom(session.at("camera")));
    } catch (const json::exception& e) {
        emit failed(tr("Opening the session failed: malformed entry: %1").arg(e.what()));
        return false;
    }
    emit finished(tr("opened session %1 (%2 entities)").arg(qpath).arg(document_.size()));
    return true;
}

void SessionController::saveWithDialog()
{
    const QString path = QFileDialog::getSaveFileName(parentWindow_, tr("Save session"), "session.scandiff", tr("scandiff session (*.scandiff)"));
    if (!path.isEmpty())
        save(path);
}

void SessionController::restoreWithDialog()
{
    const QString path = QFileDialog::getOpenFileName(parentWindow_, tr("Open session"), QString(), tr("scandiff session (*.scandiff)"));
    if (!path.isEmpty())
        restore(path);
}

} // namespace scandiff::gui
