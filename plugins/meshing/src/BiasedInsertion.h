// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! How the meshing plugin's triangulations are built (the mesh tool's and
//! height above ground's TIN): one point at a time in CGAL's spatial order, a
//! biased randomised insertion order (shuffled, then rounds each four times
//! the previous, each along a Hilbert curve), each located from the face of
//! the one before, so that Cancel is heard between points. The rounds are
//! sorted one by one rather than by CGAL::spatial_sort in one call, which
//! takes 0.4 s on 2 M points unheard; CGAL's range insertion in batches was
//! ten times slower at 16 M points.

#include <scandiff/core/Progress.h>

#include <CGAL/Spatial_sort_traits_adapter_2.h>
#include <CGAL/hilbert_sort.h>

#include <algorithm>
#include <cstddef>
#include <random>
#include <utility>
#include <vector>

namespace scandiff::plugins::detail {

//! Inserts every (point, info) pair, reordering `points`; steps `ticker` by
//! about 2 x points.size() (ordering, then insertion). At one place, the
//! vertex keeps the info of the last pair inserted there.
template <class Triangulation, class Info>
void insertInBiasedRandomOrder(Triangulation& triangulation, std::vector<std::pair<typename Triangulation::Point, Info>>& points,
                               ProgressTicker& ticker)
{
    using Pair = std::pair<typename Triangulation::Point, Info>;
    using SortTraits = CGAL::Spatial_sort_traits_adapter_2<typename Triangulation::Geom_traits, CGAL::First_of_pair_property_map<Pair>>;
    const std::size_t n = points.size();
    std::mt19937_64 shuffleDraw(0x5eed); // a fixed seed: the same triangulation on every run
    std::shuffle(points.begin(), points.end(), shuffleDraw);
    ticker.step(n / 4);
    for (std::size_t end = n; end > 0;) {
        const std::size_t begin = end > 64 ? end / 4 : 0;
        CGAL::hilbert_sort(points.begin() + static_cast<std::ptrdiff_t>(begin), points.begin() + static_cast<std::ptrdiff_t>(end),
                           SortTraits());
        ticker.step((end - begin) * 3 / 4);
        end = begin;
    }
    typename Triangulation::Face_handle hint;
    for (std::size_t i = 0; i < n; ++i) {
        const typename Triangulation::Vertex_handle vertex = triangulation.insert(points[i].first, hint);
        vertex->info() = points[i].second;
        hint = vertex->face();
        if ((i & 8191) == 8191)
            ticker.step(8192);
    }
}

} // namespace scandiff::plugins::detail
