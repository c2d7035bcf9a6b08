// SPDX-License-Identifier: GPL-3.0-or-later
// Qt Test, offscreen platform: colour scales, colourise and the histogram on
// hand-checked values, then the range, histogram and scale editor widgets
// driven with the mouse and keyboard as a user would.
// Mouse events through the platform plugin: QTest's widget mouseMove otherwise
// only moves the cursor, which the offscreen platform turns into no event.
#define QTEST_QPA_MOUSE_HANDLING

#include "colour/ColourScale.h"
#include "colour/ColourScaleEditor.h"
#include "widgets/HistogramWidget.h"
#include "widgets/RangeEditor.h"
#include "widgets/RangeSlider.h"

#include <QApplication>
#include <QCheckBox>
#include <QColorDialog>
#include <QDialogButtonBox>
#include <QDoubleSpinBox>
#include <QLabel>
#include <QLineEdit>
#include <QPushButton>
#include <QSignalSpy>
#include <QTimer>
#include <QVBoxLayout>
#include <QtTest>

#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>

using namespace scandiff::gui;
using Rgb = std::array<std::uint8_t, 3>;
using Rgba = std::array<std::uint8_t, 4>;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

const ColourScale& greyScale()
{
    static const ColourScale grey = *ColourScale::preset("Grey");
    return grey;
}

// Black -> (100,200,50) -> (200,0,250): quarter points land on whole numbers.
ColourScale evenScale()
{
    return ColourScale("even", {{0.0, 0, 0, 0}, {0.5, 100, 200, 50}, {1.0, 200, 0, 250}});
}

std::vector<Rgba> colourised(const std::vector<float>& values, double offset, const ColourScale& scale,
                             const FieldColouring& how)
{
    std::vector<std::uint8_t> rgba(4 * values.size(), 77); // 77: catches untouched bytes
    colourise(values.data(), values.size(), offset, scale, how, rgba.data());
    std::vector<Rgba> out(values.size());
    for (std::size_t i = 0; i < values.size(); ++i)
        out[i] = {rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2], rgba[4 * i + 3]};
    return out;
}

Rgba opaque(std::uint8_t v) { return {v, v, v, 255}; }

// The modal colour dialog opened by a click, once it is up.
void answerColourDialog(const QColor& colour)
{
    QTimer::singleShot(0, [colour] {
        for (QWidget* w : QApplication::topLevelWidgets()) {
            if (auto* dialog = qobject_cast<QColorDialog*>(w); dialog && dialog->isVisible()) {
                dialog->setCurrentColor(colour);
                dialog->accept();
                return;
            }
        }
        answerColourDialog(colour); // not shown yet: look again on the next turn
    });
}

} // namespace

// Readable failure messages for the colour arrays.
namespace QTest {
template <>
char* toString(const Rgb& c)
{
    return qstrdup(QString("rgb(%1, %2, %3)").arg(c[0]).arg(c[1]).arg(c[2]).toUtf8().constData());
}
template <>
char* toString(const Rgba& c)
{
    return qstrdup(QString("rgba(%1, %2, %3, %4)").arg(c[0]).arg(c[1]).arg(c[2]).arg(c[3]).toUtf8().constData());
}
} // namespace QTest

class WidgetsTest : public QObject
{
    Q_OBJECT

private slots:
    // ---- ColourScale -------------------------------------------------------

    void scaleSortsItsStopsAndRefusesInvalidOnes()
    {
        const ColourScale s("s", {{1.0, 1, 1, 1}, {0.0, 0, 0, 0}, {0.25, 2, 2, 2}});
        QCOMPARE(s.stops().size(), std::size_t(3));
        QCOMPARE(s.stops()[0].position, 0.0);
        QCOMPARE(s.stops()[1].position, 0.25);
        QCOMPARE(s.stops()[2].position, 1.0);
        QVERIFY(!s.symmetric());

        QVERIFY_EXCEPTION_THROWN(ColourScale("x", {{0.0, 0, 0, 0}}), std::invalid_argument);
        QVERIFY_EXCEPTION_THROWN(ColourScale("x", {}), std::invalid_argument);
        QVERIFY_EXCEPTION_THROWN(ColourScale("x", {{0.0, 0, 0, 0}, {1.5, 0, 0, 0}}), std::invalid_argument);
        QVERIFY_EXCEPTION_THROWN(ColourScale("x", {{-0.1, 0, 0, 0}, {1.0, 0, 0, 0}}), std::invalid_argument);
        QVERIFY_EXCEPTION_THROWN(ColourScale("x", {{0.1, 0, 0, 0}, {1.0, 0, 0, 0}}), std::invalid_argument);
        QVERIFY_EXCEPTION_THROWN(ColourScale("x", {{0.0, 0, 0, 0}, {0.9, 0, 0, 0}}), std::invalid_argument);
        QVERIFY_EXCEPTION_THROWN(ColourScale("x", {{0.0, 0, 0, 0}, {std::nan(""), 0, 0, 0}, {1.0, 0, 0, 0}}),
                                 std::invalid_argument);
    }

    void presetsAreTheDocumentedOnes()
    {
        const auto& presets = ColourScale::presets();
        QCOMPARE(presets.size(), std::size_t(19)); // CloudCompare 2.11 ships 16
        std::set<std::string> names;
        for (const ColourScale& s : presets)
            names.insert(s.name());
        QCOMPARE(names.size(), presets.size());
        // Perceptually uniform first, then the diverging ones.
        const char* leading[] = {"Viridis", "Cividis", "Magma", "Inferno", "Plasma"};
        for (std::size_t i = 0; i < std::size(leading); ++i)
            QCOMPARE(presets[i].name(), std::string(leading[i]));
        QCOMPARE(ColourScale::defaultScale().name(), std::string("Blue-Green-Yellow-Red"));
        for (const char* name : {"Grey", "Diverging Blue-White-Red", "Turbo", "HSV 360", "Terrain"})
            QVERIFY2(ColourScale::preset(name).has_value(), name);
        QVERIFY(!ColourScale::preset("viridis").has_value());
        const ColourScale bgyr = *ColourScale::preset("Blue-Green-Yellow-Red");
        QCOMPARE(bgyr.colourAt(0.0), (Rgb{0, 0, 255}));
        QCOMPARE(bgyr.colourAt(1.0 / 3.0), (Rgb{0, 255, 0}));
        QCOMPARE(bgyr.colourAt(2.0 / 3.0), (Rgb{255, 255, 0}));
        QCOMPARE(bgyr.colourAt(1.0), (Rgb{255, 0, 0}));
        // The diverging scale of signed distances: white at 0.
        QCOMPARE(ColourScale::preset("Diverging Blue-White-Red")->colourAt(0.5), (Rgb{247, 247, 247}));
    }

    void colourAtInterpolatesBetweenStops()
    {
        const ColourScale s = evenScale();
        QCOMPARE(s.colourAt(0.0), (Rgb{0, 0, 0}));
        QCOMPARE(s.colourAt(0.5), (Rgb{100, 200, 50}));
        QCOMPARE(s.colourAt(1.0), (Rgb{200, 0, 250}));
        QCOMPARE(s.colourAt(0.25), (Rgb{50, 100, 25}));
        QCOMPARE(s.colourAt(0.75), (Rgb{150, 100, 150}));
        // Clamped, and NaN counts as the start.
        QCOMPARE(s.colourAt(-3.0), (Rgb{0, 0, 0}));
        QCOMPARE(s.colourAt(7.0), (Rgb{200, 0, 250}));
        QCOMPARE(s.colourAt(std::nan("")), (Rgb{0, 0, 0}));
        // Rounded to the nearest level: 127.5 -> 128, 63.75 -> 64.
        QCOMPARE(greyScale().colourAt(0.5), (Rgb{128, 128, 128}));
        QCOMPARE(greyScale().colourAt(0.25), (Rgb{64, 64, 64}));
    }

    void equalPositionsMakeAHardEdge()
    {
        const ColourScale s("edge", {{0.0, 0, 0, 0}, {0.5, 255, 0, 0}, {0.5, 0, 0, 255}, {1.0, 0, 0, 255}});
        QCOMPARE(s.colourAt(0.5), (Rgb{0, 0, 255}));
        QCOMPARE(s.colourAt(0.25), (Rgb{128, 0, 0}));
        QCOMPARE(s.colourAt(0.75), (Rgb{0, 0, 255}));
    }

    // What "perceptually uniform" and "diverging" promise, measured in CIE
    // L* (sRGB, D65): the sequential scales' lightness rises at every step of
    // 1/200, the diverging ones' rises to a light centre and falls
    // after it, each half's ends as light as the other's within a few units.
    void perceptualScalesRiseInLightnessAndDivergingOnesPeakAtTheirCentre()
    {
        const auto lightness = [](Rgb c) {
            const auto linear = [](std::uint8_t v) {
                const double x = v / 255.0;
                return x <= 0.04045 ? x / 12.92 : std::pow((x + 0.055) / 1.055, 2.4);
            };
            const double y = 0.2126 * linear(c[0]) + 0.7152 * linear(c[1]) + 0.0722 * linear(c[2]);
            return y > 216.0 / 24389.0 ? 116.0 * std::cbrt(y) - 16.0 : y * 24389.0 / 27.0;
        };
        constexpr int kSteps = 200;
        for (const char* name : {"Viridis", "Cividis", "Magma", "Inferno", "Plasma", "Grey"}) {
            const ColourScale scale = *ColourScale::preset(name);
            QVERIFY2(!scale.symmetric(), name);
            for (int i = 1; i <= kSteps; ++i) {
                const double before = lightness(scale.colourAt((i - 1.0) / kSteps));
                const double now = lightness(scale.colourAt(double(i) / kSteps));
                QVERIFY2(now > before - 0.15, qPrintable(QString("%1 at %2: L* %3 after %4").arg(name).arg(i).arg(now).arg(before)));
            }
            QVERIFY2(lightness(scale.colourAt(1)) - lightness(scale.colourAt(0)) > 60, name);
        }
        int diverging = 0;
        for (const ColourScale& scale : ColourScale::presets()) {
            if (!scale.symmetric())
                continue;
            ++diverging;
            const QString name = QString::fromStdString(scale.name());
            QVERIFY2(name.startsWith("Diverging"), qPrintable(name));
            for (int i = 1; i <= kSteps; ++i) {
                const double before = lightness(scale.colourAt((i - 1.0) / kSteps));
                const double now = lightness(scale.colourAt(double(i) / kSteps));
                const bool rising = i <= kSteps / 2;
                QVERIFY2(rising ? now > before - 0.15 : now < before + 0.15, qPrintable(QString("%1 at %2").arg(name).arg(i)));
            }
            QVERIFY2(std::abs(lightness(scale.colourAt(0)) - lightness(scale.colourAt(1))) < 12, qPrintable(name));
            QVERIFY2(lightness(scale.colourAt(0.5)) > 85, qPrintable(name)); // zero reads as the lightest: no change
        }
        QVERIFY(diverging >= 5);
    }

    void textRoundTrips()
    {
        for (const ColourScale& s : ColourScale::presets()) {
            const std::string text = s.toText();
            QVERIFY(text.find('\n') == std::string::npos);
            const auto back = ColourScale::fromText(text);
            QVERIFY(back.has_value());
            QVERIFY(*back == s);
        }
        // A name with the format's own separators, escapes and line breaks.
        const ColourScale odd("a;name=b\\n\nc\r;stops=", {{0.0, 1, 2, 3}, {1.0 / 3.0, 4, 5, 6}, {1.0, 254, 255, 0}},
                              true);
        const std::string text = odd.toText();
        QVERIFY(text.find('\n') == std::string::npos && text.find('\r') == std::string::npos);
        const auto back = ColourScale::fromText(text);
        QVERIFY(back.has_value());
        QCOMPARE(back->name(), odd.name());
        QCOMPARE(back->stops()[1].position, 1.0 / 3.0); // every bit kept
        QVERIFY(back->symmetric());
        QVERIFY(*back == odd);
    }

    void fromTextRefusesWhatToTextDoesNotWrite()
    {
        QVERIFY(!ColourScale::fromText("").has_value());
        QVERIFY(!ColourScale::fromText("Grey").has_value());
        const std::string good = greyScale().toText();
        QVERIFY(ColourScale::fromText(good).has_value());
        QVERIFY(!ColourScale::fromText(good.substr(0, good.size() / 2)).has_value());
        const std::string head = "scandiff-colour-scale 1;symmetric=0;stops=";
        QVERIFY(ColourScale::fromText(head + "0:000000,1:ffffff;name=g").has_value());
        QVERIFY(!ColourScale::fromText(head + "0:000000;name=g").has_value());           // one stop
        QVERIFY(!ColourScale::fromText(head + "0.5:000000,1:ffffff;name=g").has_value()); // first not at 0
        QVERIFY(!ColourScale::fromText(head + "0:00000g,1:ffffff;name=g").has_value());   // not hex
        QVERIFY(!ColourScale::fromText(head + "0:000000,1:ffffff,;name=g").has_value());  // trailing comma
        QVERIFY(!ColourScale::fromText(head + "0:000000,1x:ffffff;name=g").has_value());
        QVERIFY(!ColourScale::fromText(head + "0:000000,1:ffffff;name=g\\").has_value()); // dangling escape
        QVERIFY(!ColourScale::fromText("scandiff-colour-scale 1;symmetric=2;stops=0:000000,1:ffffff;name=g")
                     .has_value());
    }

    // ---- colourise ---------------------------------------------------------

    void colouriseMapsTheColourRangeWithOffsetAndSaturation()
    {
        FieldColouring how;
        how.colourMin = 10;
        how.colourMax = 20;
        // Stored values plus the offset 10: 10, 15, 20, 12.5, 5, 30, NaN.
        const std::vector<float> values{0.f, 5.f, 10.f, 2.5f, -5.f, 20.f, kNaN};
        const auto out = colourised(values, 10.0, greyScale(), how);
        QCOMPARE(out[0], opaque(0));
        QCOMPARE(out[1], opaque(128));
        QCOMPARE(out[2], opaque(255));
        QCOMPARE(out[3], opaque(64));
        QCOMPARE(out[4], opaque(0));   // below the colour range: saturated
        QCOMPARE(out[5], opaque(255)); // above it
        QCOMPARE(out[6], opaque(150)); // NaN: the default nanColour
    }

    void colouriseLandsOnTheScaleAtStopsAndQuarters()
    {
        FieldColouring how;
        how.colourMin = -1;
        how.colourMax = 1;
        const std::vector<float> values{-1.f, -0.5f, 0.f, 0.5f, 1.f};
        const auto out = colourised(values, 0.0, evenScale(), how);
        for (std::size_t i = 0; i < values.size(); ++i) {
            const Rgb c = evenScale().colourAt((values[i] + 1.0) / 2.0);
            QCOMPARE(out[i], (Rgba{c[0], c[1], c[2], 255}));
        }
        QCOMPARE(out[1], (Rgba{50, 100, 25, 255}));
        QCOMPARE(out[3], (Rgba{150, 100, 150, 255}));
    }

    void colouriseHidesOrGreysOutsideTheVisibleRange()
    {
        FieldColouring how;
        how.colourMin = 0;
        how.colourMax = 10;
        how.visibleMin = 2;
        how.visibleMax = 8;
        const std::vector<float> values{1.f, 2.f, 5.f, 8.f, 9.f, kNaN};
        auto out = colourised(values, 0.0, greyScale(), how);
        QCOMPARE(out[0], (Rgba{0, 0, 0, 0}));
        QCOMPARE(out[1], opaque(51)); // the ends of the range are inside: 0.2 * 255
        QCOMPARE(out[2], opaque(128));
        QCOMPARE(out[3], opaque(204));
        QCOMPARE(out[4], (Rgba{0, 0, 0, 0}));
        QCOMPARE(out[5], opaque(150));

        how.outside = FieldColouring::Outside::Grey;
        how.greyColour = {1, 2, 3};
        how.showNaN = false;
        out = colourised(values, 0.0, greyScale(), how);
        QCOMPARE(out[0], (Rgba{1, 2, 3, 255}));
        QCOMPARE(out[2], opaque(128));
        QCOMPARE(out[4], (Rgba{1, 2, 3, 255}));
        QCOMPARE(out[5], (Rgba{0, 0, 0, 0}));

        how.showNaN = true;
        how.nanColour = {9, 8, 7};
        out = colourised(values, 0.0, greyScale(), how);
        QCOMPARE(out[5], (Rgba{9, 8, 7, 255}));
    }

    void colouriseKeepsTheOffsetInDouble()
    {
        // float alone cannot hold 1e6 + 0.25 apart from 1e6 + 0.5; the double sum can.
        FieldColouring how;
        how.colourMin = 1e6;
        how.colourMax = 1e6 + 1;
        const auto out = colourised({0.25f, 0.5f, 1.0f}, 1e6, greyScale(), how);
        QCOMPARE(out[0], opaque(64));
        QCOMPARE(out[1], opaque(128));
        QCOMPARE(out[2], opaque(255));
    }

    void colouriseWithAnEmptyColourRange()
    {
        FieldColouring how;
        how.colourMin = how.colourMax = 5;
        const auto out = colourised({4.f, 5.f, 6.f}, 0.0, greyScale(), how);
        QCOMPARE(out[0], opaque(0));
        QCOMPARE(out[1], opaque(128));
        QCOMPARE(out[2], opaque(255));
    }

    void colouriseOfALargeFieldMatchesPointByPoint()
    {
        // Large enough to be split over threads; each point must come out as alone.
        std::mt19937 random(7);
        std::normal_distribution<float> normal(0.f, 2.f);
        std::vector<float> values(300000);
        for (float& v : values)
            v = normal(random);
        for (std::size_t i = 0; i < values.size(); i += 997)
            values[i] = kNaN;
        FieldColouring how;
        how.colourMin = -3;
        how.colourMax = 3;
        how.visibleMin = -4;
        how.visibleMax = 5;
        const ColourScale& scale = ColourScale::defaultScale();
        const auto all = colourised(values, 0.5, scale, how);
        for (std::size_t i = 0; i < values.size(); i += 101) {
            const auto one = colourised({values[i]}, 0.5, scale, how);
            QCOMPARE(all[i], one[0]);
        }
    }

    // ---- computeHistogram --------------------------------------------------

    void histogramCountsKnownData()
    {
        std::vector<float> values{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, kNaN, std::numeric_limits<float>::infinity(),
                                  -std::numeric_limits<float>::infinity()};
        const Histogram h = computeHistogram(values.data(), values.size(), 0.0, 5);
        QCOMPARE(h.min, 0.0);
        QCOMPARE(h.max, 9.0);
        QCOMPARE(h.finiteCount, std::size_t(10));
        QCOMPARE(h.counts, (std::vector<std::size_t>{2, 2, 2, 2, 2}));

        const std::vector<float> skewed{0, 0, 0, 1, 10};
        const Histogram s = computeHistogram(skewed.data(), skewed.size(), 0.0, 10);
        QCOMPARE(s.counts, (std::vector<std::size_t>{3, 1, 0, 0, 0, 0, 0, 0, 0, 1}));
    }

    void histogramOfManyValuesIsTheOneCountedByHand()
    {
        // Far more values than one share of the threads' split (65,536): the
        // counts added over the shares are those of one pass, bin by bin.
        constexpr std::size_t kCount = 1'000'003;
        std::vector<float> values(kCount);
        for (std::size_t i = 0; i < kCount; ++i)
            values[i] = i % 997 == 0 ? kNaN : static_cast<float>(std::sin(0.001 * static_cast<double>(i)) * 40.0);
        const int bins = 37;
        const Histogram h = computeHistogram(values.data(), values.size(), 2.5, bins);
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        std::size_t finite = 0;
        for (float v : values)
            if (std::isfinite(v)) {
                lo = std::min(lo, static_cast<double>(v) + 2.5);
                hi = std::max(hi, static_cast<double>(v) + 2.5);
                ++finite;
            }
        std::vector<std::size_t> counts(bins, 0);
        const double toBin = bins / (hi - lo);
        for (float v : values)
            if (std::isfinite(v)) {
                const double x = (static_cast<double>(v) + 2.5 - lo) * toBin;
                ++counts[static_cast<std::size_t>(std::min(x, bins - 1.0))];
            }
        QCOMPARE(h.min, lo);
        QCOMPARE(h.max, hi);
        QCOMPARE(h.finiteCount, finite);
        QCOMPARE(h.counts, counts);
    }

    void histogramAppliesTheOffset()
    {
        const std::vector<float> values{0.f, 1.f, 0.5f};
        const Histogram h = computeHistogram(values.data(), values.size(), 100.0, 2);
        QCOMPARE(h.min, 100.0);
        QCOMPARE(h.max, 101.0);
        QCOMPARE(h.counts, (std::vector<std::size_t>{1, 2})); // 100.5 opens the second bin
    }

    void histogramOfEqualEmptyAndNaNOnlyData()
    {
        const std::vector<float> equal{3, 3, 3};
        Histogram h = computeHistogram(equal.data(), equal.size(), 0.0, 4);
        QCOMPARE(h.min, 3.0);
        QCOMPARE(h.max, 3.0);
        QCOMPARE(h.finiteCount, std::size_t(3));
        QCOMPARE(h.counts, (std::vector<std::size_t>{3, 0, 0, 0}));

        h = computeHistogram(nullptr, 0, 0.0, 3);
        QCOMPARE(h.finiteCount, std::size_t(0));
        QCOMPARE(h.min, 0.0);
        QCOMPARE(h.max, 0.0);
        QCOMPARE(h.counts, (std::vector<std::size_t>{0, 0, 0}));

        const std::vector<float> nans{kNaN, kNaN};
        h = computeHistogram(nans.data(), nans.size(), 1.0, 2);
        QCOMPARE(h.finiteCount, std::size_t(0));
        QCOMPARE(h.counts, (std::vector<std::size_t>{0, 0}));

        h = computeHistogram(equal.data(), equal.size(), 0.0, 0); // at least one bin
        QCOMPARE(h.counts, (std::vector<std::size_t>{3}));
    }

    // ---- RangeSlider -------------------------------------------------------

    void sliderClampsAndSignalsChanges()
    {
        RangeSlider slider;
        QCOMPARE(slider.low(), 0.0);
        QCOMPARE(slider.high(), 1.0);
        QSignalSpy spy(&slider, &RangeSlider::rangeChanged);
        slider.setBounds(0, 100);
        QCOMPARE(spy.count(), 0); // (0,1) still fits
        slider.setRange(10, 50);
        QCOMPARE(spy.count(), 1);
        QCOMPARE(spy.last().at(0).toDouble(), 10.0);
        QCOMPARE(spy.last().at(1).toDouble(), 50.0);
        slider.setRange(10, 50);
        QCOMPARE(spy.count(), 1); // no change, no signal
        slider.setRange(-5, 200);
        QCOMPARE(slider.low(), 0.0);
        QCOMPARE(slider.high(), 100.0);
        slider.setRange(80, 20);
        QCOMPARE(slider.low(), 20.0);
        QCOMPARE(slider.high(), 80.0);
        slider.setRange(std::nan(""), 30);
        QCOMPARE(slider.low(), 20.0);
        // Values are kept exactly, not rounded to the slider's steps.
        slider.setRange(12.345678901234, 56.7);
        QCOMPARE(slider.low(), 12.345678901234);
        QCOMPARE(slider.high(), 56.7);
        const int before = spy.count();
        slider.setBounds(30, 40); // narrower bounds pull the range in
        QCOMPARE(slider.low(), 30.0);
        QCOMPARE(slider.high(), 40.0);
        QCOMPARE(spy.count(), before + 1);
        slider.setBounds(50, -50); // swapped
        QCOMPARE(slider.minimum(), -50.0);
        QCOMPARE(slider.maximum(), 50.0);
        slider.setBounds(0, kInf); // refused
        QCOMPARE(slider.maximum(), 50.0);
    }

    void draggingMovesTheLowHandle()
    {
        RangeSlider slider;
        slider.resize(300, slider.sizeHint().height());
        slider.setBounds(0, 100);
        slider.setRange(20, 80);
        slider.show();
        QVERIFY(QTest::qWaitForWindowExposed(&slider));
        QSignalSpy spy(&slider, &RangeSlider::rangeChanged);
        QSignalSpy finished(&slider, &RangeSlider::dragFinished);

        const QPoint start = slider.handleCentre(RangeSlider::Handle::Low);
        const QPoint end = start + QPoint(60, 0);
        QTest::mousePress(&slider, Qt::LeftButton, {}, start);
        QTest::mouseMove(&slider, start + QPoint(30, 0));
        QTest::mouseMove(&slider, end);
        QTest::mouseRelease(&slider, Qt::LeftButton, {}, end);
        QVERIFY(spy.count() >= 1);
        QCOMPARE(finished.count(), 1);
        QCOMPARE(slider.high(), 80.0);
        QVERIFY(slider.low() > 20.0);
        QCOMPARE(spy.last().at(0).toDouble(), slider.low());
        QCOMPARE(spy.last().at(1).toDouble(), 80.0);
        // The handle follows the mouse: it is drawn where the drag ended.
        QVERIFY(std::abs(slider.handleCentre(RangeSlider::Handle::Low).x() - end.x()) <= 1);
        QCOMPARE(slider.activeHandle(), RangeSlider::Handle::Low);

        // The low handle cannot pass the high one.
        const QPoint again = slider.handleCentre(RangeSlider::Handle::Low);
        QTest::mousePress(&slider, Qt::LeftButton, {}, again);
        QTest::mouseMove(&slider, QPoint(slider.width() - 1, again.y()));
        QTest::mouseRelease(&slider, Qt::LeftButton, {}, QPoint(slider.width() - 1, again.y()));
        QCOMPARE(slider.low(), 80.0);
        QCOMPARE(slider.high(), 80.0);

        // Stacked handles: moving left takes the low one.
        const QPoint stacked = slider.handleCentre(RangeSlider::Handle::High);
        QTest::mousePress(&slider, Qt::LeftButton, {}, stacked);
        QTest::mouseMove(&slider, stacked - QPoint(50, 0));
        QTest::mouseRelease(&slider, Qt::LeftButton, {}, stacked - QPoint(50, 0));
        QVERIFY(slider.low() < 80.0);
        QCOMPARE(slider.high(), 80.0);

        // A press on the groove right of both handles brings the high one there.
        const QPoint groove(slider.width() - 3, stacked.y());
        QTest::mouseClick(&slider, Qt::LeftButton, {}, groove);
        QCOMPARE(slider.high(), 100.0);
    }

    void keyboardMovesTheActiveHandle()
    {
        RangeSlider slider;
        slider.resize(300, slider.sizeHint().height());
        slider.setBounds(0, 200);
        slider.setRange(50, 150);
        QCOMPARE(slider.activeHandle(), RangeSlider::Handle::Low);
        QTest::keyClick(&slider, Qt::Key_Right);
        QCOMPARE(slider.low(), 52.0); // 1% of the bounds
        QTest::keyClick(&slider, Qt::Key_PageDown);
        QCOMPARE(slider.low(), 32.0); // 10%
        QTest::keyClick(&slider, Qt::Key_End);
        QCOMPARE(slider.low(), 150.0); // stops at the high handle
        QTest::keyClick(&slider, Qt::Key_Home);
        QCOMPARE(slider.low(), 0.0);

        slider.show();
        QVERIFY(QTest::qWaitForWindowExposed(&slider));
        slider.setFocus();
        if (!slider.hasFocus())
            QSKIP("this platform gives no keyboard focus to the window");
        QTest::keyClick(&slider, Qt::Key_Tab);
        QCOMPARE(slider.activeHandle(), RangeSlider::Handle::High);
        QTest::keyClick(&slider, Qt::Key_Left);
        QCOMPARE(slider.high(), 148.0);
        QTest::keyClick(&slider, Qt::Key_Backtab);
        QCOMPARE(slider.activeHandle(), RangeSlider::Handle::Low);
    }

    // ---- RangeEditor -------------------------------------------------------

    void editorBoxesFollowTheSlider()
    {
        RangeEditor editor;
        auto* lowBox = editor.findChild<QDoubleSpinBox*>("lowBox");
        auto* highBox = editor.findChild<QDoubleSpinBox*>("highBox");
        QVERIFY(lowBox && highBox);
        QCOMPARE(lowBox, editor.lowBox());
        editor.setBounds(0, 100);
        QSignalSpy spy(&editor, &RangeEditor::rangeChanged);
        editor.setRange(10, 90);
        QCOMPARE(spy.count(), 1);
        QCOMPARE(lowBox->value(), 10.0);
        QCOMPARE(highBox->value(), 90.0);

        editor.slider()->setRange(30, 70);
        QCOMPARE(spy.count(), 2);
        QCOMPARE(lowBox->value(), 30.0);
        QCOMPARE(highBox->value(), 70.0);
        QCOMPARE(editor.low(), 30.0);

        // Decimals follow the span, to about the slider's resolution.
        QCOMPARE(lowBox->decimals(), 2);
        editor.setBounds(0, 1);
        QCOMPARE(lowBox->decimals(), 4);
        editor.setBounds(0, 0.001);
        QCOMPARE(highBox->decimals(), 7);
        editor.setBounds(-5000, 5000);
        QCOMPARE(highBox->decimals(), 0);
    }

    void typingInABoxMovesTheSliderOnce()
    {
        RangeEditor editor;
        editor.setBounds(0, 100);
        editor.setRange(10.123456789, 90);
        editor.show();
        QVERIFY(QTest::qWaitForWindowExposed(&editor));
        QSignalSpy spy(&editor, &RangeEditor::rangeChanged);

        QDoubleSpinBox* highBox = editor.highBox();
        highBox->setFocus();
        highBox->selectAll();
        QTest::keyClicks(highBox, "42.5");
        QTest::keyClick(highBox, Qt::Key_Return);
        QCOMPARE(spy.count(), 1);
        QCOMPARE(spy.last().at(1).toDouble(), 42.5);
        QCOMPARE(editor.high(), 42.5);
        QCOMPARE(editor.slider()->high(), 42.5);
        // The other end keeps its exact value, not the box's rounded one.
        QCOMPARE(editor.low(), 10.123456789);

        // A low end typed above the high end stops there, and the box says so.
        QDoubleSpinBox* lowBox = editor.lowBox();
        lowBox->setFocus();
        lowBox->selectAll();
        QTest::keyClicks(lowBox, "60");
        QTest::keyClick(lowBox, Qt::Key_Return);
        QCOMPARE(spy.count(), 2);
        QCOMPARE(editor.low(), 42.5);
        QCOMPARE(lowBox->value(), 42.5);
    }

    // ---- HistogramWidget ---------------------------------------------------

    void histogramBarsTakeTheScaleColour()
    {
        HistogramWidget widget;
        widget.resize(400, 160);
        Histogram h;
        h.min = 0;
        h.max = 4;
        h.counts = {10, 10, 10, 10};
        h.finiteCount = 40;
        widget.setHistogram(h);
        widget.setColouring(greyScale(), 0, 4);
        QCOMPARE(widget.axisMin(), 0.0);
        QCOMPARE(widget.axisMax(), 4.0);

        const QRect plot = widget.plotRect();
        QVERIFY(plot.width() > 300 && plot.height() > 80);
        const int y = plot.bottom() - plot.height() / 2;
        QImage image = widget.grab().toImage();
        // Bin centres 0.5 and 2.5 are at 1/8 and 5/8 of the colour range.
        QCOMPARE(image.pixelColor(widget.xOfValue(0.5), y), QColor(32, 32, 32));
        QCOMPARE(image.pixelColor(widget.xOfValue(2.5), y), QColor(159, 159, 159));

        // Marking [2, 4] washes out the first half only.
        widget.setMarkedRange(4, 2);
        QCOMPARE(widget.markedLow(), 2.0);
        QCOMPARE(widget.markedHigh(), 4.0);
        image = widget.grab().toImage();
        QVERIFY(image.pixelColor(widget.xOfValue(0.5), y) != QColor(32, 32, 32));
        QCOMPARE(image.pixelColor(widget.xOfValue(3.5), y), QColor(223, 223, 223));
    }

    // The count axis: 0 at the bottom, the tallest bar's count at its top,
    // the middle tick where a bar of that count ends, on both scales; the
    // labels fit left of the plot.
    void theCountAxisIsLabelledAtTheBarsHeights()
    {
        HistogramWidget widget;
        widget.resize(400, 160);
        Histogram h;
        h.min = 0;
        h.max = 3;
        h.counts = {123456, 61728, 99};
        h.finiteCount = 123456 + 61728 + 99;
        widget.setHistogram(h);
        widget.setColouring(greyScale(), 0, 3);
        for (bool logarithmic : {false, true}) {
            widget.setLogarithmic(logarithmic);
            const auto ticks = widget.countTicks();
            QCOMPARE(ticks.size(), std::size_t(3));
            const QRect plot = widget.plotRect();
            QCOMPARE(ticks.front().first, std::size_t(0));
            QCOMPARE(ticks.front().second, plot.bottom());
            QCOMPARE(ticks.back().first, std::size_t(123456));
            QCOMPARE(ticks.back().second, plot.top());
            const std::size_t middle = ticks[1].first;
            QCOMPARE(middle, logarithmic ? std::size_t(std::llround(std::expm1(std::log1p(123456.0) / 2))) : std::size_t(61728));
            // The tallest bar reaches the top tick, the bar of the middle count (linear) the middle one.
            const QImage image = widget.grab().toImage();
            QVERIFY(image.pixelColor(widget.xOfValue(0.5), plot.top()) != image.pixelColor(widget.xOfValue(0.5), plot.top() - 1));
            if (!logarithmic) {
                const QColor bar = image.pixelColor(widget.xOfValue(1.5), (ticks[1].second + plot.bottom()) / 2);
                QCOMPARE(image.pixelColor(widget.xOfValue(1.5), ticks[1].second), bar);
                QVERIFY(image.pixelColor(widget.xOfValue(1.5), ticks[1].second - 1) != bar);
            }
            // "123456" fits in the margin.
            QVERIFY(widget.fontMetrics().horizontalAdvance("123456") < plot.left());
        }
        widget.setHistogram({});
        QVERIFY(widget.countTicks().empty());
    }

    void draggingAMarkerEditsTheRange()
    {
        HistogramWidget widget;
        widget.resize(400, 160);
        Histogram h;
        h.min = 0;
        h.max = 10;
        h.counts = {1, 2, 3, 4, 5};
        h.finiteCount = 15;
        widget.setHistogram(h);
        widget.setMarkedRange(2, 8);
        widget.show();
        QVERIFY(QTest::qWaitForWindowExposed(&widget));
        QSignalSpy spy(&widget, &HistogramWidget::markedRangeEdited);

        const int y = widget.plotRect().center().y();
        const QPoint from(widget.xOfValue(2), y);
        const QPoint to(widget.xOfValue(5), y);
        QTest::mousePress(&widget, Qt::LeftButton, {}, from);
        QTest::mouseMove(&widget, to);
        QTest::mouseRelease(&widget, Qt::LeftButton, {}, to);
        QVERIFY(spy.count() >= 1);
        const double pixel = 10.0 / widget.plotRect().width();
        QVERIFY(std::abs(widget.markedLow() - 5.0) <= pixel);
        QCOMPARE(widget.markedHigh(), 8.0);
        QCOMPARE(spy.last().at(0).toDouble(), widget.markedLow());

        // A press away from the markers does nothing.
        const int count = spy.count();
        QTest::mouseClick(&widget, Qt::LeftButton, {}, QPoint(widget.xOfValue(7), y));
        QCOMPARE(spy.count(), count);
    }

    void histogramWithoutValuesOrWithOneValue()
    {
        HistogramWidget widget;
        widget.resize(300, 130);
        QCOMPARE(widget.axisMin(), 0.0);
        QCOMPARE(widget.axisMax(), 1.0);
        QVERIFY(!widget.grab().isNull()); // "No values", no division by zero

        const std::vector<float> equal{2, 2, 2};
        widget.setHistogram(computeHistogram(equal.data(), equal.size(), 0.0, 8));
        QVERIFY(widget.axisMin() < 2.0 && widget.axisMax() > 2.0);
        const QImage image = widget.grab().toImage();
        const QRect plot = widget.plotRect();
        // Colour range [0,1] by default: the value 2 is saturated at the top (red).
        QCOMPARE(image.pixelColor(widget.xOfValue(2.0), plot.bottom() - 5), QColor(255, 0, 0));
        QVERIFY(widget.minimumSizeHint().width() >= 250 && widget.minimumSizeHint().height() >= 120);
    }

    // ---- ColourScaleEditor -------------------------------------------------

    void scaleEditorReturnsTheEditedScale()
    {
        const ColourScale initial = ColourScale::defaultScale();
        ColourScaleEditor editor(initial);
        QCOMPARE(editor.stopCount(), 4);
        QVERIFY(editor.isValid());
        QVERIFY(editor.scale() == initial);
        auto* ok = editor.findChild<QDialogButtonBox*>("buttonBox")->button(QDialogButtonBox::Ok);
        QVERIFY(ok->isEnabled());

        editor.findChild<QLineEdit*>("nameEdit")->setText("Mine");
        editor.findChild<QCheckBox*>("symmetricBox")->setChecked(true);
        editor.positionBox(1)->setValue(0.8); // after the yellow stop now
        editor.setStopColour(2, QColor(10, 20, 30));
        const ColourScale edited = editor.scale();
        QCOMPARE(edited.name(), std::string("Mine"));
        QVERIFY(edited.symmetric());
        QCOMPARE(edited.stops().size(), std::size_t(4));
        QCOMPARE(edited.stops()[1].position, 2.0 / 3.0);
        QCOMPARE((Rgb{edited.stops()[1].r, edited.stops()[1].g, edited.stops()[1].b}), (Rgb{10, 20, 30}));
        QCOMPARE(edited.stops()[2].position, 0.8);
        QCOMPARE((Rgb{edited.stops()[2].r, edited.stops()[2].g, edited.stops()[2].b}), (Rgb{0, 255, 0}));
    }

    void scaleEditorColourButtonOpensTheColourDialog()
    {
        ColourScaleEditor editor(greyScale());
        editor.show();
        QVERIFY(QTest::qWaitForWindowExposed(&editor));
        answerColourDialog(QColor(200, 100, 50));
        editor.colourButton(1)->click();
        QCOMPARE(editor.stopColour(1), QColor(200, 100, 50));
        const ColourScale s = editor.scale();
        QCOMPARE(s.colourAt(1.0), (Rgb{200, 100, 50}));
    }

    void scaleEditorRefusesInvalidEdits()
    {
        ColourScaleEditor editor(greyScale());
        auto* ok = editor.findChild<QDialogButtonBox*>("buttonBox")->button(QDialogButtonBox::Ok);
        auto* message = editor.findChild<QLabel*>("messageLabel");
        QVERIFY(ok && message);

        editor.removeStop(); // no selection: the last one
        QCOMPARE(editor.stopCount(), 1);
        QVERIFY(!editor.isValid());
        QVERIFY(!ok->isEnabled());
        QVERIFY(!message->text().isEmpty());
        QVERIFY(!editor.problem().isEmpty());
        QVERIFY(editor.scale() == greyScale()); // the last valid one

        // Adding brings back the missing end, coloured as the scale was there.
        QCOMPARE(editor.addStop(), 1);
        QVERIFY(editor.isValid());
        QVERIFY(ok->isEnabled());
        QVERIFY(editor.problem().isEmpty());
        QVERIFY(editor.scale() == greyScale());

        // The next one goes into the widest gap.
        QCOMPARE(editor.addStop(), 1);
        QCOMPARE(editor.positionBox(1)->value(), 0.5);
        QCOMPARE(editor.stopColour(1), QColor(128, 128, 128));
        QCOMPARE(editor.scale().stops().size(), std::size_t(3));

        editor.positionBox(0)->setValue(0.1);
        QVERIFY(!editor.isValid());
        QVERIFY(!ok->isEnabled());
        editor.positionBox(0)->setValue(0.0);
        QVERIFY(editor.isValid());

        editor.findChild<QLineEdit*>("nameEdit")->clear();
        QVERIFY(!editor.isValid());
        QVERIFY(!ok->isEnabled());
    }

    // ---- A look at them together --------------------------------------------

    void screenshotOfHistogramAndRangeEditor()
    {
        std::mt19937 random(3);
        std::normal_distribution<float> normal(0.02f, 0.01f);
        std::vector<float> values(200000);
        for (float& v : values)
            v = normal(random);
        const Histogram h = computeHistogram(values.data(), values.size(), 0.0, 64);

        QWidget panel;
        auto* layout = new QVBoxLayout(&panel);
        auto* histogram = new HistogramWidget(&panel);
        auto* range = new RangeEditor(&panel);
        layout->addWidget(histogram);
        layout->addWidget(range);
        QObject::connect(range, &RangeEditor::rangeChanged, histogram, &HistogramWidget::setMarkedRange);
        histogram->setHistogram(h);
        histogram->setColouring(ColourScale::defaultScale(), h.min, h.max);
        range->setBounds(h.min, h.max);
        range->setRange(0.01, 0.035);
        QCOMPARE(histogram->markedLow(), 0.01);
        panel.resize(360, 230);
        panel.show();
        QVERIFY(QTest::qWaitForWindowExposed(&panel));
        QVERIFY(panel.grab().save("/tmp/widgets.png"));

        ColourScaleEditor editor(*ColourScale::preset("Viridis"));
        editor.show();
        QVERIFY(QTest::qWaitForWindowExposed(&editor));
        QVERIFY(editor.grab().save("/tmp/scale-editor.png"));
    }
};

QTEST_MAIN(WidgetsTest)
#include "WidgetsTest.moc"
