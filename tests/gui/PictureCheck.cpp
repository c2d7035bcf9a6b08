// SPDX-License-Identifier: GPL-3.0-or-later
// Checks the workbench's screenshot of the demo cloud as a person would look
// at it: the cloud is there, in its colours, framed by "zoom to all".
// Usage: scandiff_picture_check PICTURE.png; exit status 0 when it holds.
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

int main(int argc, char** argv)
{
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s PICTURE.png\n", argv[0]);
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
