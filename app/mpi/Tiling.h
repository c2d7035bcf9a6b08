// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The square tiles scandiff-mpi splits a comparison into, and which rank owns
//! which. Plain C++ (no MPI), so the tests check it directly.
//!
//! Tiles are squares of the XY plane anchored at the global origin (0, 0): a
//! point's tile depends on its world coordinates only, never on the data's
//! extent or the number of ranks, so every rank computes the same keys.

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

namespace scandiff::mpi {

struct TileKey
{
    std::int64_t x = 0, y = 0;
    friend bool operator<(const TileKey& a, const TileKey& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; }
    friend bool operator==(const TileKey& a, const TileKey& b) { return a.x == b.x && a.y == b.y; }
};

struct TileKeyHash
{
    std::size_t operator()(const TileKey& k) const
    {
        return std::hash<std::int64_t>()(k.x * 73856093 ^ k.y * 19349663);
    }
};

//! The value of the tile a point lies in, looked up once per run of points
//! in one tile: consecutive points of a scan mostly share a tile.
template <class Value>
class LastTile
{
public:
    //! `lookup(key)` gives the value when the key is not the last one.
    template <class Lookup>
    Value& of(const TileKey& key, Lookup&& lookup)
    {
        if (!known_ || !(key == key_)) {
            value_ = lookup(key);
            key_ = key;
            known_ = true;
        }
        return value_;
    }
    //! After what the values came from changed.
    void forget() { known_ = false; }

private:
    TileKey key_;
    Value value_{};
    bool known_ = false;
};

class TileGrid
{
public:
    //! `size` in metres, > 0.
    explicit TileGrid(double size) : size_(size) {}
    double size() const { return size_; }
    TileKey tileOf(double x, double y) const;
    //! The tile's square [min, max) in world X and Y.
    Eigen::Vector2d tileMin(const TileKey& key) const;
    Eigen::Vector2d tileMax(const TileKey& key) const;
    //! How far (in X or Y, the larger of the two) a point of `key` lies inside the tile's
    //! square grown by `halo`: the radius of the largest XY ball around it
    //! that the grown square holds.
    double depthInGrownTile(const TileKey& key, double halo, double x, double y) const;

private:
    double size_;
};

//! Tiles to ranks by their point counts, largest first, each to the rank with
//! the fewest points so far (ties to the lower rank; equal counts in key order):
//! the same answer on every rank. Returns the rank of every tile.
std::map<TileKey, int> assignTiles(const std::map<TileKey, std::uint64_t>& pointsPerTile, int ranks);

//! Which points lie within `halo` (in X and Y) of a set of tiles: the points a
//! rank must hold of the reference. One hash look-up for most points: a
//! point's tile is owned (kept), far from every owned tile (dropped), or on a
//! border within the halo's reach (tested against the owned tiles around it).
class HaloRegion
{
public:
    HaloRegion(const TileGrid& grid, const std::vector<TileKey>& tiles, double halo);
    bool contains(double x, double y) const;
    bool owns(const TileKey& key) const { return owned_.count(key) != 0; }
    //! Whether the XY box [lo, hi] comes within the halo of an owned tile
    //! (a triangle a rank must hold of a reference mesh).
    bool intersects(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const;

private:
    enum Status : std::uint8_t { Far, Owned, Border };
    Status statusOf(const TileKey& key) const;

    TileGrid grid_;
    std::unordered_set<TileKey, TileKeyHash> owned_;
    std::unordered_set<TileKey, TileKeyHash> border_;
    double halo_;
    std::int64_t reach_; //!< tiles a halo spans beyond a tile's edge
    mutable LastTile<Status> lastStatus_;
};

//! Squares of the XY plane, each a centre and a half-side (the reach of a
//! point whose search must be widened), indexed by cells as large as the
//! largest: which of them an XY box touches, looking only at the cells the box
//! spans and one around. An infinite half-side reaches everywhere.
class ReachIndex
{
public:
    ReachIndex(std::vector<Eigen::Vector2d> centres, std::vector<double> halfSides, double minimumCell);
    //! Whether the box [lo, hi] (a point when lo = hi) touches one of the squares.
    bool touches(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const;

private:
    std::vector<Eigen::Vector2d> centres_;
    std::vector<double> halfSides_;
    bool everywhere_ = false;
    TileGrid cells_;
    std::unordered_map<TileKey, std::vector<std::size_t>, TileKeyHash> byCell_;
};

} // namespace scandiff::mpi
