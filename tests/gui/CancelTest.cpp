// SPDX-License-Identifier: GPL-3.0-or-later
//! Cancel as a user presses it, on a run as long as the one the trial found
//! uncancellable: C2C between two 2 M-point clouds with the quadric model, both
//! ways, on the worker thread, with the Cancel button clicked (a mouse event
//! delivered to the progress dialog's native window, the way the windowing
//! system delivers it) or Escape pressed in the main window, during each stage:
//! each way's octree and each way's distances. Also during the reading and the
//! writing of a 2 M-point file. Each run must end cancelled, say "Cancelling..."
//! at once and leave the document as it was. How long each took to stop after
//! the press is printed (tests assert no timings; docs/benchmarks.md has them).

#include "controllers/DistanceController.h"
#include "controllers/FileController.h"
#include "document/Document.h"

#include <scandiff/plugins/PluginRegistry.h>

#include <QApplication>
#include <QElapsedTimer>
#include <QProgressDialog>
#include <QPushButton>
#include <QSignalSpy>
#include <QTemporaryDir>
#include <QTimer>
#include <QWindow>
#include <QtTest>

#include <cmath>
#include <functional>
#include <random>

using namespace scandiff;

namespace {

//! A gently undulating 200 x 200 m terrain with 5 mm of noise: two epochs are
//! two samplings of it, so the quadric model works as on real data.
PointCloud terrain(std::size_t count, unsigned seed)
{
    PointCloud cloud;
    cloud.resize(count);
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> across(0.0f, 200.0f);
    std::normal_distribution<float> noise(0.0f, 0.005f);
    for (Eigen::Vector3f& p : cloud.positions()) {
        const float x = across(random), y = across(random);
        p = {x, y, 2.0f * std::sin(x / 17.0f) * std::cos(y / 23.0f) + noise(random)};
    }
    return cloud;
}

enum class Press { CancelButton, EscapeInMainWindow };

//! Watches the progress dialog and presses Cancel once its label starts with
//! `stage` and its bar has reached `fromPermille`.
class CancelPresser : public QObject
{
public:
    CancelPresser(QWidget* mainWindow, QString stage, int fromPermille, Press press)
        : mainWindow_(mainWindow), stage_(std::move(stage)), fromPermille_(fromPermille), press_(press)
    {
        connect(&poll_, &QTimer::timeout, this, [this] { check(); });
        poll_.start(5);
    }
    bool pressed() const { return pressed_; }
    bool saidCancelling() const { return saidCancelling_; }
    //! Milliseconds from the press to the end of the run, once `ended()` was called.
    qint64 stopMilliseconds() const { return stopMilliseconds_; }
    void ended()
    {
        poll_.stop();
        if (pressed_)
            stopMilliseconds_ = sincePress_.elapsed();
    }

private:
    void check()
    {
        if (pressed_)
            return;
        for (QWidget* widget : QApplication::topLevelWidgets()) {
            auto* dialog = qobject_cast<QProgressDialog*>(widget);
            if (!dialog || !dialog->labelText().startsWith(stage_) || dialog->value() < fromPermille_)
                continue;
            if (press_ == Press::EscapeInMainWindow) {
                // Wherever the keyboard focus is: the main window until the dialog shows.
                QWindow* focus = QGuiApplication::focusWindow();
                QTest::keyClick(focus ? focus : mainWindow_->windowHandle(), Qt::Key_Escape);
            } else {
                if (!dialog->isVisible())
                    return; // wait until the user can see it
                auto* button = dialog->findChild<QPushButton*>();
                QTest::mouseClick(dialog->windowHandle(), Qt::LeftButton, Qt::NoModifier,
                                  button->mapTo(dialog, button->rect().center()));
            }
            pressed_ = true;
            sincePress_.start();
            saidCancelling_ = dialog->labelText() == QObject::tr("Cancelling...");
            return;
        }
    }

    QWidget* mainWindow_;
    QString stage_;
    int fromPermille_;
    Press press_;
    QTimer poll_;
    bool pressed_ = false, saidCancelling_ = false;
    QElapsedTimer sincePress_;
    qint64 stopMilliseconds_ = -1;
};

} // namespace

class CancelTest : public QObject
{
    Q_OBJECT

private slots:
    void initTestCase()
    {
        mainWindow_.resize(800, 600);
        mainWindow_.show();
        QVERIFY(QTest::qWaitForWindowExposed(&mainWindow_));
        compared_ = document_.add("compared", terrain(2'000'000, 1));
        reference_ = document_.add("reference", terrain(2'000'000, 2));
    }

    void cancelStopsTheDistancesInEveryStage_data()
    {
        QTest::addColumn<QString>("stage");
        QTest::addColumn<int>("fromPermille");
        QTest::addColumn<int>("press");
        const auto escape = static_cast<int>(Press::EscapeInMainWindow), button = static_cast<int>(Press::CancelButton);
        QTest::newRow("first way, octree, Escape") << "Compared -> reference: Ordering" << 0 << escape;
        QTest::newRow("first way, distances, button") << "Compared -> reference: Distances" << 300 << button;
        QTest::newRow("second way, octree, button") << "Reference -> compared: Ordering" << 0 << button;
        QTest::newRow("second way, distances, Escape") << "Reference -> compared: Distances" << 500 << escape;
    }

    void cancelStopsTheDistancesInEveryStage()
    {
        QFETCH(QString, stage);
        QFETCH(int, fromPermille);
        QFETCH(int, press);
        gui::DistanceController controller(document_, &mainWindow_);
        QSignalSpy failed(&controller, &gui::DistanceController::failed);
        QSignalSpy cancelled(&controller, &gui::DistanceController::cancelled);
        CancelPresser presser(&mainWindow_, stage, fromPermille, static_cast<Press>(press));
        const bool done = controller.runCloudToCloud(compared_, reference_, {{"model", "quadric"}, {"both-ways", "true"}});
        presser.ended();
        QVERIFY2(presser.pressed(), "the stage was never shown");
        QVERIFY(presser.saidCancelling());
        QVERIFY(!done);
        QCOMPARE(failed.count(), 0); // stopping is no error
        QCOMPARE(cancelled.count(), 1);
        QCOMPARE(cancelled.at(0).at(0).toString(), QString("C2C was cancelled"));
        QVERIFY(!document_.item(compared_).points().field("c2c_distance"));
        QVERIFY(!document_.item(reference_).points().field("c2c_distance"));
        qInfo("stopped %lld ms after the press", static_cast<long long>(presser.stopMilliseconds()));
    }

    void cancelStopsReadingAndWriting()
    {
        const PluginRegistry registry = makePluginRegistry();
        gui::FileController files(registry, document_, &mainWindow_);
        QTemporaryDir folder;
        // ASCII: a 2 M-point binary PLY reads in about the time the dialog takes
        // to show on a quiet machine, and the press could come after the end.
        const QString path = folder.filePath("big.asc");
        QVERIFY(files.exportEntity(compared_, path)); // uncancelled: the file to read

        QSignalSpy failed(&files, &gui::FileController::failed);
        QSignalSpy cancelled(&files, &gui::FileController::cancelled);
        CancelPresser whileReading(&mainWindow_, "Reading", 200, Press::EscapeInMainWindow);
        const std::size_t before = document_.size();
        QVERIFY(files.open({path}, true).empty());
        whileReading.ended();
        QVERIFY(whileReading.pressed());
        QCOMPARE(document_.size(), before);
        qInfo("reading stopped %lld ms after the press", static_cast<long long>(whileReading.stopMilliseconds()));

        const QString second = folder.filePath("second.asc");
        CancelPresser whileWriting(&mainWindow_, "Writing", 200, Press::EscapeInMainWindow);
        QVERIFY(!files.exportEntity(compared_, second));
        whileWriting.ended();
        QVERIFY(whileWriting.pressed());
        QVERIFY(!QFileInfo::exists(second)); // nothing half-written left behind
        QCOMPARE(failed.count(), 0); // stopping is no error
        QCOMPARE(cancelled.count(), 2);
        QCOMPARE(QDir(folder.path()).entryList(QDir::Files), QStringList{"big.asc"});
    }

private:
    QWidget mainWindow_;
    gui::Document document_;
    gui::EntityId compared_ = 0, reference_ = 0;
};

QTEST_MAIN(CancelTest)
#include "CancelTest.moc"
