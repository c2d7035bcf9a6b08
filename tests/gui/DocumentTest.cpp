// SPDX-License-Identifier: GPL-3.0-or-later
// Qt Test, offscreen platform: the document, the colouring of entities, the
// entity tree and the split controller, without a 3D view.
#include "controllers/SplitController.h"
#include "document/Document.h"
#include "panels/EntityTree.h"
#include "panels/ScalarFieldPanel.h"
#include "view/EntityColouring.h"
#include "widgets/HistogramWidget.h"
#include "widgets/RangeEditor.h"

#include <QComboBox>
#include <QDoubleSpinBox>
#include <QPushButton>
#include <QCheckBox>
#include <QSignalSpy>
#include <QTemporaryDir>
#include <QFile>
#include <random>
#include <QtTest>

#include <array>
#include <cmath>

using namespace scandiff;
using gui::EntityId;

namespace {

//! Four points with field d = 0, 1, 2, NaN (stored around an offset of 100).
PointCloud fourPoints()
{
    PointCloud cloud;
    cloud.resize(4);
    ScalarField& d = cloud.addField("d");
    d.setOffset(100.0);
    for (std::size_t i = 0; i < 3; ++i) {
        cloud.positions()[i] = {float(i), 0, 0};
        d.setValue(i, double(i));
    }
    d.values()[3] = std::nanf("");
    return cloud;
}

} // namespace

//! Whether `f` throws (anything).
template <class F> bool throwsAnything(F&& f)
{
    try {
        f();
    } catch (...) {
        return true;
    }
    return false;
}

class DocumentTest : public QObject
{
    Q_OBJECT

private slots:
    void initTestCase() { qRegisterMetaType<gui::EntityId>("EntityId"); }

    void colouringHidesOrGreysOutsideTheThresholds()
    {
        gui::Document document;
        const EntityId id = document.add("four", fourPoints());
        QCOMPARE(document.item(id).display.activeField, std::string("d")); // the first field is active
        gui::FieldDisplay display = document.fieldDisplay(id, "d");
        display.low = 0.5;
        display.high = 1.5;
        document.setFieldDisplay(id, "d", display);
        std::vector<std::uint8_t> rgba(16);
        gui::ColourLegend legend = gui::colourEntity(document.item(id).points(), document.item(id).display, rgba.data());
        QVERIFY(legend.shown);
        QCOMPARE(legend.min, 0.0); // the scale spans the field's range, not the thresholds
        QCOMPARE(legend.max, 2.0);
        QCOMPARE(int(rgba[3]), 0);    // 0: below, hidden
        QCOMPARE(int(rgba[7]), 255);  // 1: inside
        QCOMPARE(int(rgba[11]), 0);   // 2: above, hidden
        QCOMPARE(int(rgba[15]), 255); // NaN: shown in the no-value grey
        // The inside point has the scale's middle colour (1 in [0, 2]).
        const auto middle = display.scale.colourAt(0.5);
        QCOMPARE(int(rgba[4]), int(middle[0]));
        QCOMPARE(int(rgba[5]), int(middle[1]));
        QCOMPARE(int(rgba[6]), int(middle[2]));

        document.setOutsideMode(id, gui::FieldColouring::Outside::Grey);
        gui::colourEntity(document.item(id).points(), document.item(id).display, rgba.data());
        QCOMPARE(int(rgba[3]), 255);
        QCOMPARE(int(rgba[0]), int(gui::FieldColouring{}.greyColour[0]));

        // A diverging scale is centred on 0.
        display.scale = *gui::ColourScale::preset("Diverging Blue-White-Red");
        document.setFieldDisplay(id, "d", display);
        legend = gui::colourEntity(document.item(id).points(), document.item(id).display, rgba.data());
        QCOMPARE(legend.min, -2.0);
        QCOMPARE(legend.max, 2.0);
    }

    void colourRangeIsApartFromTheThresholds()
    {
        // The trial's C2M field: -32 to +58 m, with the changes of interest within 2 m.
        gui::Document document;
        PointCloud cloud;
        cloud.resize(4);
        ScalarField& d = cloud.addField("d");
        const double values[4] = {-32.0, 1.0, 1.5, 58.0};
        for (std::size_t i = 0; i < 4; ++i)
            d.setValue(i, values[i]);
        const EntityId id = document.add("c2m", std::move(cloud));
        gui::FieldDisplay display;
        display.colourLow = -2.0;
        display.colourHigh = 2.0;
        display.low = -1.2; // thresholds: only |d| <= 1.2 shown
        display.high = 1.2;
        document.setFieldDisplay(id, "d", display);
        std::vector<std::uint8_t> rgba(16);
        const gui::ColourLegend legend = gui::colourEntity(document.item(id).points(), document.item(id).display, rgba.data());
        QCOMPARE(legend.min, -2.0);
        QCOMPARE(legend.max, 2.0);
        auto colourOf = [&](std::size_t i) { return std::array<int, 3>{rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]}; };
        auto scaleAt = [&](double t) {
            const auto c = display.scale.colourAt(t);
            return std::array<int, 3>{c[0], c[1], c[2]};
        };
        QCOMPARE(colourOf(1), scaleAt(0.75)); // 1 m in [-2, 2]: no longer the colour of every small value
        QCOMPARE(int(rgba[7]), 255);
        QCOMPARE(int(rgba[11]), 0); // 1.5 m: coloured within the range but beyond the threshold, hidden
        document.setOutsideMode(id, gui::FieldColouring::Outside::Grey);
        display.low = -100.0;
        display.high = 100.0;
        document.setFieldDisplay(id, "d", display);
        gui::colourEntity(document.item(id).points(), document.item(id).display, rgba.data());
        QCOMPARE(colourOf(0), scaleAt(0.0)); // beyond the colour range: the end colours
        QCOMPARE(colourOf(3), scaleAt(1.0));
        QCOMPARE(colourOf(2), scaleAt(0.875));

        // Symmetric around 0: 0 at the middle of the scale, whatever the field's extent.
        display.colourLow = display.colourHigh = std::numeric_limits<double>::infinity();
        display.colourLow = -display.colourLow;
        display.symmetric = true;
        document.setFieldDisplay(id, "d", display);
        const gui::ColourLegend symmetric = gui::colourEntity(document.item(id).points(), document.item(id).display, rgba.data());
        QCOMPARE(symmetric.min, -58.0);
        QCOMPARE(symmetric.max, 58.0);

        // The panel edits the same state: the colour range editor, the box, Automatic.
        gui::ScalarFieldPanel panel(document);
        panel.showEntity(id);
        QVERIFY(panel.symmetricBox()->isChecked());
        panel.symmetricBox()->setChecked(false);
        QVERIFY(!document.fieldDisplay(id, "d").symmetric);
        QCOMPARE(panel.colourRangeEditor()->low(), -32.0);
        panel.colourRangeEditor()->setRange(-2.0, 2.0);
        QCOMPARE(document.fieldDisplay(id, "d").colourLow, -2.0);
        QCOMPARE(document.fieldDisplay(id, "d").colourHigh, 2.0);
        QCOMPARE(document.fieldDisplay(id, "d").low, -100.0); // the thresholds did not move
        QTest::mouseClick(panel.automaticColoursButton(), Qt::LeftButton);
        QVERIFY(std::isinf(document.fieldDisplay(id, "d").colourLow));
        QCOMPARE(panel.colourRangeEditor()->high(), 58.0);
    }

    void flagsAndLabelsAreCategoriesInTheViewTheBarAndTheHistogram()
    {
        // Issue 50, defect 8: the histogram drew labels on a rainbow and the
        // significance flag on a 0-1 ramp.
        gui::Document document;
        PointCloud cloud;
        cloud.resize(6);
        cloud.addField("m3c2_significant").values() = {0, 1, 1, 0, std::nanf(""), 1};
        cloud.addField("region_id").values() = {1, 2, 3, 2, 1, 7};
        cloud.addField("distance").values() = {0, 1, 1, 0, 0.5f, 1};
        const EntityId id = document.add("cores", std::move(cloud));
        const PointCloud& points = document.item(id).points();
        QVERIFY(gui::isFlagField(*points.field("m3c2_significant")));
        QVERIFY(!gui::isFlagField(*points.field("distance"))); // a 0.5 among them: a measure
        QVERIFY(!gui::isFlagField(*points.field("region_id")));
        document.setActiveField(id, "m3c2_significant");
        std::vector<std::uint8_t> rgba(24);
        const gui::ColourLegend legend = gui::colourEntity(points, document.item(id).display, rgba.data());
        auto colourOf = [&](std::size_t i) { return std::array<std::uint8_t, 3>{rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]}; };
        QCOMPARE(colourOf(0), gui::categoryColour(false, 0));
        QCOMPARE(colourOf(1), gui::categoryColour(false, 1));
        QVERIFY(colourOf(0) != colourOf(1));
        QCOMPARE(legend.categories.size(), std::size_t(2)); // two swatches, not a ramp
        QCOMPARE(legend.categories[1].second, colourOf(1));
        // The histogram's bars in the points' colours, for the flag and for labels.
        gui::ScalarFieldPanel panel(document);
        panel.showEntity(id);
        QVERIFY(panel.histogram()->categorical());
        const auto asQColor = [](const std::array<std::uint8_t, 3>& c) { return QColor(c[0], c[1], c[2]); };
        QCOMPARE(panel.histogram()->colourOfValue(1.0), asQColor(colourOf(1)));
        QCOMPARE(panel.histogram()->colourOfValue(0.02), asQColor(colourOf(0)));
        document.setActiveField(id, "region_id");
        panel.showEntity(id);
        QVERIFY(panel.histogram()->categorical());
        QCOMPARE(panel.histogram()->colourOfValue(7.0), asQColor(gui::labelColour(7)));
        QCOMPARE(panel.histogram()->colourOfValue(3.0), asQColor(gui::labelColour(3)));
        document.setActiveField(id, "distance");
        panel.showEntity(id);
        QVERIFY(!panel.histogram()->categorical()); // a measure: the scale again
    }

    void labelsGetDistinctColoursAndNeutralIsGrey()
    {
        gui::Document document;
        PointCloud cloud;
        cloud.resize(5);
        ScalarField& ids = cloud.addField("region_id");
        const float values[5] = {1, 2, 3, 2, std::nanf("")};
        ids.values().assign(values, values + 5);
        cloud.addField("distance").values() = {1, 2, 3, 2, 0};
        const EntityId id = document.add("regions", std::move(cloud));
        document.setActiveField(id, "region_id");
        QVERIFY(gui::isLabelField(*document.item(id).points().field("region_id")));
        QVERIFY(!gui::isLabelField(*document.item(id).points().field("distance"))); // a measure, whatever its values
        std::vector<std::uint8_t> rgba(20);
        const gui::ColourLegend legend = gui::colourEntity(document.item(id).points(), document.item(id).display, rgba.data());
        auto colourOf = [&](std::size_t i) { return std::array<std::uint8_t, 3>{rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]}; };
        QCOMPARE(colourOf(0), gui::labelColour(1));
        QCOMPARE(colourOf(1), gui::labelColour(2));
        QCOMPARE(colourOf(3), colourOf(1)); // same label, same colour
        QVERIFY(colourOf(0) != colourOf(1) && colourOf(1) != colourOf(2) && colourOf(0) != colourOf(2));
        // The legend lists each label with its colour, not a ramp from 1 to 3.
        QCOMPARE(legend.categories.size(), std::size_t(3));
        QCOMPARE(legend.categories[2].first, 3L);
        QCOMPARE(legend.categories[2].second, gui::labelColour(3));
        // A non-integer value makes it a measure again.
        ScalarField fractional("region_id", 1);
        fractional.setValue(0, 1.5);
        QVERIFY(!gui::isLabelField(fractional));

        // Neutral: one grey, no legend.
        document.setActiveField(id, "");
        document.setNeutral(id, true);
        const gui::ColourLegend none = gui::colourEntity(document.item(id).points(), document.item(id).display, rgba.data());
        QVERIFY(!none.shown);
        QCOMPARE(colourOf(4), gui::kNeutralGrey);
    }

    void panelForgetsThePreviousFieldOnACloudWithout()
    {
        gui::Document document;
        gui::ScalarFieldPanel panel(document);
        const EntityId withField = document.add("four", fourPoints());
        gui::FieldDisplay display = document.fieldDisplay(withField, "d");
        display.low = 0.5;
        display.high = 1.5;
        document.setFieldDisplay(withField, "d", display);
        panel.showEntity(withField);
        QCOMPARE(panel.rangeEditor()->low(), 0.5);
        PointCloud plain;
        plain.resize(2);
        const EntityId byHeight = document.add("plain", std::move(plain));
        panel.showEntity(byHeight);
        // No range or marker of the previous cloud stays on show.
        QCOMPARE(panel.rangeEditor()->low(), 0.0);
        QCOMPARE(panel.rangeEditor()->high(), 1.0);
        QVERIFY(std::isinf(panel.histogram()->markedLow()) && std::isinf(panel.histogram()->markedHigh()));
        QCOMPARE(panel.histogram()->histogram().finiteCount, std::size_t(0));
    }

    // The histogram's CSV holds the bins drawn, each count the brute-force
    // count of the values in it (the last bin closed), over the field's range.
    void theHistogramExportsAsTheBinsItDraws()
    {
        gui::Document document;
        gui::ScalarFieldPanel panel(document);
        PointCloud cloud;
        cloud.resize(10'000);
        ScalarField& d = cloud.addField("d");
        d.setOffset(250.0);
        std::mt19937 random(7);
        std::normal_distribution<double> normal(250.0, 0.3);
        for (std::size_t i = 0; i < cloud.size(); ++i)
            d.setValue(i, i % 101 == 0 ? std::nan("") : normal(random));
        const EntityId id = document.add("normal", std::move(cloud));
        panel.showEntity(id);
        QTemporaryDir folder;
        const QString path = folder.filePath("d-histogram.csv");
        QString error;
        QVERIFY2(panel.exportHistogram(path, &error), qPrintable(error));
        QFile file(path);
        QVERIFY(file.open(QIODevice::ReadOnly | QIODevice::Text));
        const QStringList lines = QString::fromUtf8(file.readAll()).split('\n', Qt::SkipEmptyParts);
        QCOMPARE(lines.front(), QString("bin_min,bin_max,count"));
        const Histogram& drawn = panel.histogram()->histogram();
        QCOMPARE(std::size_t(lines.size() - 1), drawn.counts.size());
        const ScalarField& field = *document.item(id).points().field("d");
        std::size_t total = 0;
        for (int row = 1; row < lines.size(); ++row) {
            const QStringList cells = lines[row].split(',');
            QCOMPARE(cells.size(), 3);
            const double low = cells[0].toDouble(), high = cells[1].toDouble();
            const auto count = static_cast<std::size_t>(cells[2].toDouble());
            const bool last = row + 1 == lines.size();
            std::size_t byHand = 0;
            for (std::size_t i = 0; i < field.size(); ++i) {
                const double v = field.value(i);
                byHand += v >= low && (v < high || (last && v <= high));
            }
            QCOMPARE(count, byHand);
            QCOMPARE(count, drawn.counts[std::size_t(row - 1)]);
            total += count;
        }
        QCOMPARE(total, std::size_t(10'000 - 100));
        // No field, or a place that cannot be written: refused with a reason, nothing left behind.
        QVERIFY(!panel.exportHistogram("/nonexistent-folder/h.csv", &error) && !error.isEmpty());
        PointCloud plain;
        plain.resize(3);
        panel.showEntity(document.add("plain", std::move(plain)));
        error.clear();
        QVERIFY(!panel.exportHistogram(folder.filePath("none.csv"), &error) && !error.isEmpty());
        QVERIFY(!QFile::exists(folder.filePath("none.csv")));
    }

    // The panel keeps the width of its dock whatever the names it lists (the
    // 19 scales, long field names): it once grew past the window's edge.
    void thePanelStaysNarrowWithLongNames()
    {
        gui::Document document;
        gui::ScalarFieldPanel panel(document);
        panel.showEntity(document.add("x", fourPoints()));
        const int usual = panel.minimumSizeHint().width();
        PointCloud cloud = fourPoints();
        cloud.addField("m3c2_distance_uncertainty_at_the_projection_scale");
        panel.showEntity(document.add("a cloud with a rather long name for a scan of 2019", std::move(cloud)));
        QCOMPARE(panel.minimumSizeHint().width(), usual);
        // Nor the scales' names: the box is narrower than one sized to the longest.
        QComboBox sizedToNames;
        for (int i = 0; i < panel.scaleBox()->count(); ++i)
            sizedToNames.addItem(panel.scaleBox()->itemText(i));
        QVERIFY(panel.scaleBox()->minimumSizeHint().width() < sizedToNames.minimumSizeHint().width());
        QCOMPARE(panel.scaleBox()->count(), int(ColourScale::presets().size()));
    }

    void aRenameIsUndoneAndRedone()
    {
        gui::Document document;
        const EntityId id = document.add("scan", fourPoints());
        document.forgetUndo();
        QSignalSpy renamed(&document, &gui::Document::renamed);
        document.rename(id, "scan 2019");
        document.rename(id, "scan 2019"); // the same name: nothing to undo
        QCOMPARE(document.undoText(), QString("Undo rename to 'scan 2019'"));
        document.undo();
        QCOMPARE(document.item(id).name, QString("scan"));
        QVERIFY(!document.canUndo());
        QCOMPARE(document.redoText(), QString("Redo rename to 'scan 2019'"));
        document.redo();
        QCOMPARE(document.item(id).name, QString("scan 2019"));
        QCOMPARE(renamed.count(), 3);
    }

    // The scissors keep what the user chose: both parts, the inside or the
    // outside alone (shown), each holding exactly the points a brute force
    // puts there (points hidden by the view never inside); undone, the cut goes.
    void theScissorsKeepTheChosenPartAndNothingIsLost()
    {
        // A 20 x 20 grid at UTM-like coordinates, seen from above: screen x, y
        // = global x, y minus the corner (w = 1).
        PointCloud grid;
        grid.setOrigin(Eigen::Vector3d(512000, 5403000, 100));
        grid.resize(400);
        for (std::size_t i = 0; i < 400; ++i)
            grid.positions()[i] = Eigen::Vector3f(float(i % 20), float(i / 20), 0);
        Eigen::Matrix4d toScreen = Eigen::Matrix4d::Identity();
        toScreen(0, 3) = -512000;
        toScreen(1, 3) = -5403000;
        const std::vector<Eigen::Vector2d> triangle{{-0.5, -0.5}, {12.7, -0.5}, {-0.5, 12.7}};
        const auto insideByHand = [](std::size_t i) { return i % 20 + i / 20 <= 12; }; // under the hypotenuse x + y = 12.2
        const auto hidden = [](std::size_t i) { return i % 7 == 0; }; // e.g. beyond a threshold
        using Keep = gui::SplitController::Keep;
        for (Keep keep : {Keep::Both, Keep::Inside, Keep::Outside}) {
            gui::Document document;
            gui::SplitController splits(document);
            const EntityId id = document.add("grid", grid.clone());
            QCOMPARE(splits.cutWithPolygon(triangle, toScreen, [&](EntityId, std::size_t i) { return !hidden(i); }, keep), 1);
            const std::vector<EntityId> parts = document.children(id);
            QCOMPARE(parts.size(), std::size_t(keep == Keep::Both ? 2 : 1));
            QVERIFY(!document.item(id).display.visible);
            std::size_t expectedInside = 0;
            for (std::size_t i = 0; i < 400; ++i)
                expectedInside += insideByHand(i) && !hidden(i);
            const std::size_t expected = keep == Keep::Outside ? 400 - expectedInside : expectedInside;
            const gui::Document::Item& kept = document.item(parts.front());
            QCOMPARE(kept.points().size(), expected);
            QVERIFY(kept.display.visible);
            // Every kept point is one of the grid's, on the side chosen.
            for (const Eigen::Vector3f& p : kept.points().positions()) {
                const auto i = static_cast<std::size_t>(std::lround(p.y()) * 20 + std::lround(p.x()));
                QCOMPARE(insideByHand(i) && !hidden(i), keep != Keep::Outside);
            }
            if (keep == Keep::Both) {
                QCOMPARE(document.item(parts.back()).points().size(), 400 - expectedInside);
                QVERIFY(!document.item(parts.back()).display.visible);
            }
            document.undo();
            QVERIFY(document.children(id).empty());
            QVERIFY(document.item(id).display.visible);
        }
    }

    // Colour bar titles fit the bar's narrow frame: long field names break
    // after an underscore, short ones stay on one line.
    void aLongColourBarTitleIsWrapped()
    {
        QCOMPARE(QString::fromStdString(gui::wrappedTitle("c2c_distance")), QString("c2c_distance"));
        QCOMPARE(QString::fromStdString(gui::wrappedTitle("height_above_ground")), QString("height_above_\nground"));
        QCOMPARE(QString::fromStdString(gui::wrappedTitle("m3c2_distance_uncertainty")), QString("m3c2_\ndistance_\nuncertainty"));
        QCOMPARE(QString::fromStdString(gui::wrappedTitle("height")), QString("height"));
        QCOMPARE(QString::fromStdString(gui::wrappedTitle("a very long title here")), QString("a very long\ntitle here"));
        QCOMPARE(QString::fromStdString(gui::wrappedTitle("averyveryverylongword")), QString("averyveryverylongword"));
        QCOMPARE(QString::fromStdString(gui::wrappedTitle("")), QString(""));
    }

    // The view colours a large cloud's points as its frames gather them:
    // every stride-th point of a chunk from some first, in any order. Each
    // part must get the very bytes a whole colouring gives, and leave the
    // other points alone; for every kind of colouring, thresholds and NaN
    // included, and a field shaded by the cloud's own colours.
    void aColouringInPartsGivesEachPointTheColourOfTheWhole()
    {
        constexpr std::size_t kPoints = 100'003;
        PointCloud cloud;
        cloud.resize(kPoints);
        std::mt19937 random(7);
        std::uniform_real_distribution<float> uniform(-5, 5);
        cloud.addField("c2c_distance");
        cloud.addField("region_id");
        ScalarField& distance = *cloud.field("c2c_distance");
        ScalarField& region = *cloud.field("region_id");
        std::vector<Rgb8>& colours = cloud.enableColors();
        for (std::size_t i = 0; i < kPoints; ++i) {
            cloud.positions()[i] = {uniform(random), uniform(random), uniform(random)};
            distance.setValue(i, i % 97 == 0 ? std::numeric_limits<double>::quiet_NaN() : uniform(random));
            region.setValue(i, static_cast<double>(i % 23));
            colours[i] = Rgb8{static_cast<std::uint8_t>(i % 251), static_cast<std::uint8_t>(i % 13 * 19), 77};
        }
        // Chunks as the view cuts them, strides as its slices take them.
        const std::size_t cuts[] = {0, 40'000, 65'536, kPoints};
        const std::size_t strides[] = {1, 2, 13, 600};
        for (int kind = 0; kind < 5; ++kind) {
            gui::DisplayState display;
            display.outside = kind == 1 ? gui::FieldColouring::Outside::Grey : gui::FieldColouring::Outside::Hide;
            if (kind <= 1) {
                display.activeField = "c2c_distance";
                display.fields["c2c_distance"].low = -1.25;
                display.fields["c2c_distance"].high = 3.5;
                display.fields["c2c_distance"].scale = ColourScale::presets()[1];
            } else if (kind == 2) {
                display.activeField = "region_id";
                display.fields["region_id"].high = 17;
            } else if (kind == 3) {
                display.activeField = "c2c_distance";
                display.blendColours = true;
            } else {
                display.neutral = true;
            }
            std::vector<std::uint8_t> whole(4 * kPoints);
            gui::colourEntity(cloud, display, whole.data());
            const gui::EntityColourer colourer(cloud, display);
            QCOMPARE(colourer.colouredInParts(), kind <= 3);
            for (std::size_t stride : strides) {
                std::vector<std::uint8_t> parts(4 * kPoints, 1);
                const std::size_t first = std::min<std::size_t>(stride - 1, 5);
                for (std::size_t c = 0; c + 1 < std::size(cuts); ++c)
                    colourer.colour(parts.data(), cuts[c], cuts[c + 1], stride, first);
                for (std::size_t c = 0; c + 1 < std::size(cuts); ++c)
                    for (std::size_t i = cuts[c]; i < cuts[c + 1]; ++i) {
                        const bool taken = i >= cuts[c] + first && (i - cuts[c] - first) % stride == 0;
                        for (int k = 0; k < 4; ++k)
                            if (parts[4 * i + k] != (taken ? whole[4 * i + k] : 1))
                                QFAIL(qPrintable(QString("kind %1, stride %2, point %3").arg(kind).arg(stride).arg(i)));
                    }
            }
        }
    }

    // A field shown over the cloud's photo: each point's field colour times
    // 0.35 + 0.65 x the luminance of its own colour; hidden points stay hidden;
    // offered only on a cloud with colours; kept by the document.
    void aFieldIsShadedByTheCloudsOwnColoursWhenAsked()
    {
        PointCloud cloud = fourPoints();
        cloud.enableColors() = {Rgb8{255, 255, 255}, Rgb8{0, 0, 0}, Rgb8{200, 100, 50}, Rgb8{10, 20, 30}};
        gui::DisplayState display;
        display.activeField = "d";
        display.fields["d"].high = 1.5; // hides the point of value 2
        std::vector<std::uint8_t> plain(16), blended(16);
        gui::colourEntity(cloud, display, plain.data());
        display.blendColours = true;
        gui::colourEntity(cloud, display, blended.data());
        for (std::size_t i = 0; i < 4; ++i) {
            const Rgb8 own = cloud.colors()[i];
            const double shade = 0.35 + 0.65 * (0.2126 * own.r + 0.7152 * own.g + 0.0722 * own.b) / 255.0;
            QCOMPARE(blended[4 * i + 3], plain[4 * i + 3]);
            for (int k = 0; k < 3; ++k) {
                const auto expected = plain[4 * i + 3] == 0 ? plain[4 * i + k] : static_cast<std::uint8_t>(std::lround(plain[4 * i + k] * shade));
                QCOMPARE(blended[4 * i + k], expected);
            }
        }
        QCOMPARE(plain[4 * 2 + 3], std::uint8_t(0)); // value 2: hidden either way
        QCOMPARE(blended[0], plain[0]);                // white keeps the field's colour

        gui::Document document;
        gui::ScalarFieldPanel panel(document);
        const EntityId coloured = document.add("photo", std::move(cloud));
        document.setActiveField(coloured, "d");
        panel.showEntity(coloured);
        QVERIFY(panel.blendColoursBox()->isEnabled());
        panel.blendColoursBox()->setChecked(true);
        QVERIFY(document.item(coloured).display.blendColours);
        const EntityId bare = document.add("bare", fourPoints());
        panel.showEntity(bare);
        QVERIFY(!panel.blendColoursBox()->isEnabled() && !panel.blendColoursBox()->isChecked());
    }

    void undoRestoresADeletionAChangeAndAField()
    {
        gui::Document document;
        gui::EntityTree tree(document);
        QVERIFY(!document.canUndo());
        const EntityId parent = document.add("four", fourPoints());
        const EntityId child = document.add("part", fourPoints(), parent);
        document.setVisible(child, false);
        // A deletion (with its descendant) comes back with ids, tree and display.
        document.remove(parent);
        QVERIFY(!document.contains(parent) && !document.contains(child));
        QVERIFY(document.canUndo());
        QVERIFY(document.undoText().contains("four"));
        document.undo();
        QVERIFY(document.contains(parent) && document.contains(child));
        QCOMPARE(document.item(child).parent, parent);
        QVERIFY(!document.item(child).display.visible);
        QCOMPARE(tree.entityRow(child)->parent(), tree.entityRow(parent));
        QVERIFY(!document.canUndo());
        // A tool's change of the data comes back exactly.
        PointCloud moved = fourPoints();
        moved.positions()[0] = {9, 9, 9};
        document.replaceData(parent, std::move(moved));
        QCOMPARE(document.item(parent).points().positions()[0], Eigen::Vector3f(9, 9, 9));
        document.undo();
        QCOMPARE(document.item(parent).points().positions()[0], Eigen::Vector3f(0, 0, 0));
        // A recomputed field gets its previous values back; a new one goes.
        ScalarField again("d", 4);
        document.addField(parent, std::move(again));
        QVERIFY(std::isnan(document.item(parent).points().field("d")->value(0)));
        document.undo();
        QCOMPARE(document.item(parent).points().field("d")->value(1), 1.0);
        document.addField(parent, ScalarField("extra", 4));
        document.undo();
        QVERIFY(!document.item(parent).points().field("extra"));
        // A group (a deletion of several entities, a tool's outputs) is undone as one.
        const EntityId third = document.add("third", fourPoints());
        {
            const gui::Document::UndoGroup group(document, "delete of 2 entities");
            document.remove(child);
            document.remove(third);
        }
        QCOMPARE(document.undoText(), QString("Undo delete of 2 entities"));
        document.undo();
        QVERIFY(document.contains(child) && document.contains(third));
        // Undoing a change keeps what the user set on the display since.
        PointCloud changed = fourPoints();
        document.replaceData(parent, std::move(changed));
        document.setVisible(parent, false);
        document.undo();
        QVERIFY(!document.item(parent).display.visible);
        // A field that cannot be added (wrong size) leaves the undo step as it was.
        document.addField(parent, ScalarField("kept", 4));
        QVERIFY(throwsAnything([&] { document.addField(parent, ScalarField("bad", 3)); }));
        QCOMPARE(document.undoText(), QString("Undo field kept of 'four'"));
        // Opening a session (clear) forgets it.
        document.remove(child);
        document.clear();
        QVERIFY(!document.canUndo());
    }

    void undoAndRedoAreHistoriesThatCoverSplitsAndTheScissors()
    {
        // Issue 50, defect 3: one level of undo, and the scissors could not be undone.
        gui::Document document;
        gui::SplitController splits(document);
        const EntityId id = document.add("four", fourPoints());
        QVERIFY(!document.canUndo() && !document.canRedo());
        // Three actions, undone in turn and redone in turn, every value back.
        document.addField(id, ScalarField("first", 4));
        ScalarField second("second", 4);
        second.setValue(2, 7.5);
        document.addField(id, std::move(second));
        document.remove(id);
        QVERIFY(!document.contains(id));
        document.undo();
        QVERIFY(document.contains(id));
        QCOMPARE(document.redoText(), QString("Redo delete 'four'"));
        document.undo();
        QVERIFY(!document.item(id).points().field("second"));
        document.undo();
        QVERIFY(!document.item(id).points().field("first"));
        QVERIFY(!document.canUndo());
        document.redo();
        document.redo();
        QCOMPARE(document.item(id).points().field("second")->value(2), 7.5);
        QVERIFY(document.item(id).points().field("first"));
        document.redo();
        QVERIFY(!document.contains(id));
        QVERIFY(!document.canRedo());
        document.undo();
        QVERIFY(document.contains(id));
        // A new action after an undo empties the redo history.
        document.undo();
        QVERIFY(document.canRedo());
        document.addField(id, ScalarField("third", 4));
        QVERIFY(!document.canRedo());

        // The clipping box's extraction (the scissors' path): undone, its parts
        // go and the cloud is shown again; redone, the same parts come back.
        CropBox box;
        box.centre = Eigen::Vector3d(0.5, 0, 0);
        box.size = Eigen::Vector3d(1.2, 1, 1);
        QCOMPARE(splits.extractInBox(box), 1);
        const std::vector<EntityId> parts = document.children(id);
        QCOMPARE(parts.size(), std::size_t(2));
        QVERIFY(!document.item(id).display.visible);
        QCOMPARE(document.undoText(), QString("Undo extract in the clipping box"));
        document.undo();
        QVERIFY(document.children(id).empty());
        QVERIFY(document.item(id).display.visible);
        document.redo();
        QCOMPARE(document.children(id), parts);
        QCOMPARE(document.item(parts.front()).points().size(), std::size_t(3)); // x = 0, 1 and the fourth point at the origin
        QVERIFY(!document.item(id).display.visible);
        // A split by field range too.
        document.undo();
        const EntityId inside = splits.split(id, "d", 1.5, 2.0).first;
        QVERIFY(inside != gui::kNoEntity);
        document.undo();
        QVERIFY(!document.contains(inside));
        QVERIFY(document.item(id).display.visible);
        // The history is bounded: the oldest actions go.
        for (std::size_t k = 0; k < gui::Document::kUndoLevels + 5; ++k)
            document.addField(id, ScalarField("f" + std::to_string(k), 4));
        std::size_t levels = 0;
        while (document.canUndo()) {
            document.undo();
            ++levels;
        }
        QCOMPARE(levels, gui::Document::kUndoLevels);
    }

    void treeMirrorsTheDocument()
    {
        gui::Document document;
        gui::EntityTree tree(document);
        const EntityId id = document.add("four", fourPoints());
        QVERIFY(tree.entityRow(id));
        QCOMPARE(tree.entityRow(id)->checkState(0), Qt::Checked);
        QVERIFY(document.item(id).display.visible);
        // Unticking hides the entity.
        tree.entityRow(id)->setCheckState(0, Qt::Unchecked);
        QVERIFY(!document.item(id).display.visible);
        // A new field appears under the cloud; clicking it makes it active.
        ScalarField e("e", 4);
        document.addField(id, std::move(e));
        QVERIFY(tree.fieldRow(id, "e"));
        QCOMPARE(document.item(id).display.activeField, std::string("e"));
        emit tree.itemClicked(tree.fieldRow(id, "d"), 0);
        QCOMPARE(document.item(id).display.activeField, std::string("d"));
        // Derived entities sit under their parent, and go with it.
        const EntityId child = document.add("part", fourPoints(), id);
        QCOMPARE(tree.entityRow(child)->parent(), tree.entityRow(id));
        document.remove(id);
        QVERIFY(!document.contains(child));
        QVERIFY(!tree.entityRow(child));
        QCOMPARE(tree.topLevelItemCount(), 0);
    }

    void aTypedBoundSetsBothEndsOfASymmetricRange()
    {
        // Issue 50, defect 2: Symmetric ticked, 0.02 typed as the maximum: the
        // minimum becomes -0.02 at once (it stayed at -11.909).
        gui::Document document;
        PointCloud cloud = fourPoints();
        cloud.field("d")->setValue(0, -11.5); // exact in the float view
        cloud.field("d")->setValue(2, 5.0);
        const EntityId id = document.add("signed", std::move(cloud));
        gui::FieldDisplay display = document.fieldDisplay(id, "d");
        display.symmetric = true;
        document.setFieldDisplay(id, "d", display);
        gui::ScalarFieldPanel panel(document);
        panel.showEntity(id);
        QCOMPARE(panel.colourRangeEditor()->low(), -11.5);
        QCOMPARE(panel.colourRangeEditor()->high(), 11.5);
        panel.colourRangeEditor()->highBox()->setValue(0.02);
        const auto range = [&] { return gui::colourRange(*document.item(id).points().field("d"), document.fieldDisplay(id, "d")); };
        QCOMPARE(range().first, -0.02);
        QCOMPARE(range().second, 0.02);
        QCOMPARE(document.fieldDisplay(id, "d").colourLow, -0.02);
        QCOMPARE(panel.colourRangeEditor()->low(), -0.02);
        QCOMPARE(panel.colourRangeEditor()->high(), 0.02);
        // The minimum typed sets the maximum the same way, and so does a drag of one end.
        panel.colourRangeEditor()->lowBox()->setValue(-3.0);
        QCOMPARE(range().second, 3.0);
        QCOMPARE(panel.colourRangeEditor()->high(), 3.0);
        panel.colourRangeEditor()->setRange(-3.0, 0.5);
        QCOMPARE(range().first, -0.5);
        QCOMPARE(panel.colourRangeEditor()->low(), -0.5);
    }

    void aSplitPartShowsTheColourRangeItIsColouredWith()
    {
        // Issue 50, defect 6: a part whose values all lie above its parent's
        // colour range showed 0.5133..0.5133 while its bar showed the range.
        gui::Document document;
        gui::SplitController splits(document);
        const EntityId id = document.add("four", fourPoints());
        gui::FieldDisplay display = document.fieldDisplay(id, "d");
        display.colourLow = 0.0;
        display.colourHigh = 1.0;
        document.setFieldDisplay(id, "d", display);
        const EntityId part = splits.split(id, "d", 1.5, 2.0).first;
        QVERIFY(part != gui::kNoEntity);
        QCOMPARE(document.item(part).points().size(), std::size_t(1)); // value 2, above the colour range
        gui::ScalarFieldPanel panel(document);
        panel.showEntity(part);
        const auto [low, high] = gui::colourRange(*document.item(part).points().field("d"), document.fieldDisplay(part, "d"));
        QCOMPARE(low, 0.0);
        QCOMPARE(high, 1.0);
        QCOMPARE(panel.colourRangeEditor()->low(), low);
        QCOMPARE(panel.colourRangeEditor()->high(), high);
    }

    void panelThresholdsAndSplit()
    {
        gui::Document document;
        gui::ScalarFieldPanel panel(document);
        gui::SplitController splits(document);
        connect(&panel, &gui::ScalarFieldPanel::splitRequested, &splits, &gui::SplitController::split);
        const EntityId id = document.add("four", fourPoints());
        panel.showEntity(id);
        QCOMPARE(panel.fieldBox()->currentText(), QString("d"));
        QCOMPARE(panel.rangeEditor()->low(), 0.0);
        QCOMPARE(panel.rangeEditor()->high(), 2.0);
        panel.rangeEditor()->setRange(1.5, 2.0);
        QCOMPARE(document.fieldDisplay(id, "d").low, 1.5);
        QVERIFY(panel.insideText().contains("1 of 4"));
        // A range holding no point splits nothing and says so.
        QSignalSpy refused(&splits, &gui::SplitController::failed);
        QCOMPARE(splits.split(id, "d", 5.0, 6.0).first, gui::kNoEntity);
        QCOMPARE(refused.count(), 1);
        QCOMPARE(document.size(), std::size_t(1));
        QVERIFY(document.item(id).display.visible);
        QSignalSpy done(&splits, &gui::SplitController::finished);
        QTest::mouseClick(panel.splitButton(), Qt::LeftButton);
        QCOMPARE(done.count(), 1);
        const std::vector<EntityId> ids = document.ids();
        QCOMPARE(ids.size(), std::size_t(3));
        QCOMPARE(document.item(ids[1]).points().size(), std::size_t(1)); // value 2
        QCOMPARE(document.item(ids[2]).points().size(), std::size_t(3)); // 0, 1 and NaN
        QCOMPARE(document.item(ids[1]).parent, id);
        QVERIFY(!document.item(ids[2]).display.visible);
        // Values are compared with the offset applied (stored as value - 100).
        QCOMPARE(document.item(ids[1]).points().field("d")->value(0), 2.0);
    }
};

QTEST_MAIN(DocumentTest)
#include "DocumentTest.moc"
