// SPDX-License-Identifier: GPL-3.0-or-later
// Checks the workbench's screenshot of the demo cloud as a person would look
// at it: the cloud is there, in its colours, framed by "zoom to all".
// Usage: scandiff_picture_check PICTURE.png; exit status 0 when it holds.
//        scandiff_picture_check --legend PICTURE.png: a cloud coloured by a
//        scalar field, its colour bar drawn whole (below).
//
// The background is a grey gradient; the demo cloud (PCL's region-growing
// tutorial, one colour per region) is saturated colours. The picture must
// show it covering 3-70 % of the frame, in at least 6 of 12 hues, its extent
// spanning at least half the frame's height (zoomed to fit) and touching no
// edge (nothing cut).
#include <QColor>
#include <QImage>

#include <cstdio>
#include <set>
#include <string>

namespace {

bool light(const QColor& c) { return c.valueF() > 0.75 && c.hsvSaturationF() < 0.25; }

//! The colour bar of a view coloured by a field: a tall column of saturated
//! pixels in the right third, and its title and labels (light text) drawn
//! whole: none of their pixels within 3 columns of the right edge, where
//! VTK's labels used to run off ("c2c_distanc", "3.789e").
int checkLegend(const QImage& picture, const char* name)
{
    int barColumn = -1;
    for (int x = picture.width() - 1; x >= picture.width() * 2 / 3 && barColumn < 0; --x) {
        int saturated = 0;
        for (int y = 0; y < picture.height(); ++y)
            saturated += picture.pixelColor(x, y).hsvSaturationF() > 0.6 && picture.pixelColor(x, y).valueF() > 0.4;
        if (saturated >= picture.height() / 2)
            barColumn = x;
    }
    int lightAtEdge = 0, lightBesideBar = 0;
    for (int y = 0; y < picture.height(); ++y)
        for (int x = picture.width() * 2 / 3; x < picture.width(); ++x)
            if (light(picture.pixelColor(x, y)))
                (x >= picture.width() - 3 ? lightAtEdge : lightBesideBar) += 1;
    std::printf("%s: colour bar at column %d, %d light pixels beside it, %d at the right edge\n", name, barColumn, lightBesideBar, lightAtEdge);
    if (barColumn < 0 || lightBesideBar < 50 || lightAtEdge > 0) {
        std::fprintf(stderr, "%s: the colour bar is missing or its text is cut at the view's edge\n", name);
        return 1;
    }
    return 0;
}

} // namespace

int main(int argc, char** argv)
{
    if (argc == 3 && std::string(argv[1]) == "--legend") {
        const QImage picture(argv[2]);
        if (picture.isNull()) {
            std::fprintf(stderr, "%s: no picture\n", argv[2]);
            return 1;
        }
        return checkLegend(picture, argv[2]);
    }
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s [--legend] PICTURE.png\n", argv[0]);
        return 2;
    }
    const QImage picture(argv[1]);
    if (picture.isNull() || picture.width() < 320 || picture.height() < 240) {
        std::fprintf(stderr, "%s: no picture of a usable size\n", argv[1]);
        return 1;
    }
    std::size_t coloured = 0;
    std::set<int> hues;
    int left = picture.width(), right = -1, top = picture.height(), bottom = -1;
    for (int y = 0; y < picture.height(); ++y)
        for (int x = 0; x < picture.width(); ++x) {
            const QColor c = picture.pixelColor(x, y);
            if (c.hsvSaturationF() < 0.3 || c.valueF() < 0.15)
                continue; // the grey background, the white scale bar, dark shading
            ++coloured;
            hues.insert(c.hsvHue() / 30);
            left = std::min(left, x);
            right = std::max(right, x);
            top = std::min(top, y);
            bottom = std::max(bottom, y);
        }
    const double share = static_cast<double>(coloured) / (static_cast<double>(picture.width()) * picture.height());
    std::printf("%s: %.1f %% coloured, %zu hues, extent x %d-%d y %d-%d of %dx%d\n", argv[1], 100 * share, hues.size(), left, right,
                top, bottom, picture.width(), picture.height());
    const bool framed = bottom - top >= picture.height() / 2 && left > 0 && top > 0 && right < picture.width() - 1 &&
                        bottom < picture.height() - 1;
    if (share < 0.03 || share > 0.7 || hues.size() < 6 || !framed) {
        std::fprintf(stderr, "%s: the demo cloud is not shown as expected\n", argv[1]);
        return 1;
    }
    return 0;
}
