// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Change segmentation from the workbench (thesis 000 chapter 3): a dialog made
//! from the declarations `scandiff-cli segment` uses, the run on a worker
//! thread with progress and Cancel, the new fields (region_id, changed, chi2...)
//! added to the cloud, each region listed under it in the tree, and the export
//! of the regions as PLY, DXF and CSV. The algorithms are core's
//! runSegmentation / regionReport, the files io's exportRegions.

#include "document/Document.h"

#include <scandiff/core/segmentation/RegionReport.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <QDialog>
#include <QObject>

#include <map>
#include <string>
#include <vector>

class QComboBox;

namespace scandiff::gui {

class ParameterForm;

class SegmentationDialog : public QDialog
{
    Q_OBJECT
public:
    SegmentationDialog(const Document& document, EntityId input, QWidget* parent = nullptr);
    EntityId input() const;
    //! The other epoch for the volume between epochs; kNoEntity for none.
    EntityId reference() const;
    std::map<std::string, std::string> values() const;
    ParameterForm* form() const { return form_; }

private:
    QComboBox* input_;
    QComboBox* reference_;
    ParameterForm* form_;
};

class SegmentationController : public QObject
{
    Q_OBJECT
public:
    SegmentationController(const PluginRegistry& registry, Document& document, QWidget* parentWindow);

    void runInteractively(EntityId current);
    //! Runs on `input` with parameter text as the dialog gives it; `reference`
    //! (or kNoEntity) gives the volumes. Adds the fields and one child entity
    //! per region (the largest first, at most kMaxRegionEntities). False and
    //! failed() on error or cancellation.
    bool run(EntityId input, EntityId reference, const std::map<std::string, std::string>& parameters);
    //! The report of the last run on `id` (empty if none).
    const std::vector<RegionStatistics>& report(EntityId id) const;
    //! Writes regions.ply, region_NNNN.ply, regions.dxf and regions.csv of the
    //! cloud `id` (which must hold region_id) into `folder`; with dxfPoints the
    //! DXF also draws each region's points (as `segment --dxf-points` does).
    bool exportRegions(EntityId id, const QString& folder, bool dxfPoints = false);
    //! Asks for the folder, then whether the DXF should hold the points too.
    void exportRegionsWithDialog(EntityId id);
    //! Whether `id` (or, for a region's own entity, its cloud) has regions to export.
    bool hasRegions(EntityId id) const;

    static constexpr std::size_t kMaxRegionEntities = 100;

signals:
    void finished(const QString& summary);
    void failed(const QString& message);
    //! The user stopped a run: no error, nothing changed.
    void cancelled(const QString& message);
    void resultReady(EntityId id);

private:
    const PluginRegistry& registry_;
    Document& document_;
    QWidget* parentWindow_;
    std::map<EntityId, std::vector<RegionStatistics>> reports_;
    std::map<EntityId, std::string> distanceFields_;
    std::map<EntityId, std::vector<EntityId>> regionEntities_; //!< the region entities listed under each cloud
    bool dxfPointsChoice_ = false; //!< the export dialog's last answer, offered again
};

} // namespace scandiff::gui
