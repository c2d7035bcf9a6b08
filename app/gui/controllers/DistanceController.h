// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Cloud-to-cloud and cloud-to-mesh distances from the workbench: a dialog
//! made from the same declarations as `scandiff-cli c2c`/`c2m`, the run on a
//! worker thread with progress and Cancel, the fields added to the document.
//! The computation itself is core's runCloudToCloud / cloudToMesh.

#include "document/Document.h"

#include <QDialog>
#include <QObject>

#include <map>
#include <string>

class QComboBox;

namespace scandiff::gui {

class ParameterForm;

enum class DistanceKind { CloudToCloud, CloudToMesh };

//! Reference and compared entities plus the generated parameter form.
class DistanceDialog : public QDialog
{
    Q_OBJECT
public:
    DistanceDialog(DistanceKind kind, const Document& document, QWidget* parent = nullptr);
    EntityId reference() const;
    EntityId compared() const;
    void setReference(EntityId id);
    void setCompared(EntityId id);
    std::map<std::string, std::string> values() const;
    ParameterForm* form() const { return form_; }

private:
    QComboBox* reference_;
    QComboBox* compared_;
    ParameterForm* form_;
};

//! How the reference is shown after a comparison (a preference, kept in QSettings).
enum class ReferenceAfterComparison
{
    Grey, //!< one neutral grey, so that only the distances are in colour (the default)
    Hide, //!< hidden
    Keep  //!< as it was
};

class DistanceController : public QObject
{
    Q_OBJECT
public:
    DistanceController(Document& document, QWidget* parentWindow);

    static ReferenceAfterComparison referenceAfterComparison();
    static void setReferenceAfterComparison(ReferenceAfterComparison choice);

    //! Opens the dialog (reference: the first suitable entity, compared: the
    //! current one or the last cloud), then runs.
    void runInteractively(DistanceKind kind, EntityId current);
    //! Runs with parameter text as the dialog gives it; false (and failed()) on
    //! error or cancellation. The compared entity receives c2c_distance (and the
    //! other fields asked for) or c2m_distance; with both-ways the reference too.
    bool runCloudToCloud(EntityId compared, EntityId reference, const std::map<std::string, std::string>& parameters);
    bool runCloudToMesh(EntityId compared, EntityId reference, const std::map<std::string, std::string>& parameters);

signals:
    void finished(const QString& summary);
    void failed(const QString& message);
    //! The user stopped a run: no error, nothing changed.
    void cancelled(const QString& message);
    //! The entity whose new field should be shown.
    void resultReady(EntityId id);

private:
    //! Shows the reference as the preference says, unless it received distances itself (both ways).
    void showReference(EntityId referenceId, bool gotDistances);

    Document& document_;
    QWidget* parentWindow_;
};

} // namespace scandiff::gui
