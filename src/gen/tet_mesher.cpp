// Graded conforming tetrahedral meshes from a volume: a balanced octree whose cubes are coned into tets.
//
// 1. Octree over the volume's box: root cubes of about equal physical sides, stretched per axis to fit the
//    box exactly, at most 19 levels in all. A cube is split while it lies above level L0 (the coarsest
//    level that leaves room for 16× more cells than the coarse grid holds), or while its indicator
//    (max − min of the voxels it covers) × ∛(its side in voxels) exceeds τ. Cubes whose maximum is below the
//    threshold are never split: none of their tets is kept. So cells are fine where the values change (edges
//    of the brain, folds of the cortex) and coarse where they are uniform; τ sets how fine, continuously.
//    (With the side to the first power, MRI texture gave almost uniform meshes: p99/p1 of the volumes 9 at 1M
//    cells; with the cube root, 35.)
// 2. τ is found by regula falsi on a count of the tree's leaves (a walk that stores nothing), then corrected
//    by the exact count of the built mesh until that count is within 5 % of --cells.
// 3. 2:1 balance over all 26 neighbours (a leaf at most one level coarser than any leaf it touches).
// 4. Each leaf becomes tets conforming with its neighbours by a rule that depends only on the shared face:
//    a face whose neighbour is finer is cut into its 4 sub-squares, each fanned from its centre; any other
//    face is fanned from its centre to its corners and to the midpoints of its split edges (an edge is
//    split where a finer leaf touches it). Each face triangle is coned to the cube's centre: 24 to 96 tets
//    per leaf, none axis-aligned. Both sides of a face see the same split state, so the mesh conforms.
// 5. A tet is kept when the volume at its centroid is ≥ the threshold. Vertices live on a lattice of a
//    quarter of a leaf's side; each belongs to the leaf whose half-open box holds it, which numbers the
//    vertices it owns that a kept tet uses; prefix sums over the leaves (in Morton order) give global ids.
//    Everything is a function of the inputs alone, so the file does not depend on the thread count.
// 6. Vertices move by up to 1/64 of their leaf's side per axis (a hash of position and seed): small enough
//    that no tet can invert (the smallest height of a coned tet is 0.18 of its leaf's side).
#include "gen/mesher.h"

#include "core/morton.h"
#include "core/progress.h"
#include <uvr/error.h>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_scan.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>

namespace uvr {

namespace {

constexpr int kMaxLevel = 19;
constexpr int64_t kRootSide = int64_t(1) << kMaxLevel; // finest units per side of the root cube
constexpr double kTetsPerLeafGuess = 36.0;             // about what the brain scan gives
constexpr double kJitter = 1.0 / 64.0;
constexpr int kSlots = 125; // 5×5×5 lattice points of a leaf at a quarter of its side

uint64_t morton(int64_t x, int64_t y, int64_t z) { return mortonCode(uint32_t(x), uint32_t(y), uint32_t(z)); }

struct Mask128 {
  uint64_t word[2] = {0, 0};
  void set(int bit) { word[bit >> 6] |= uint64_t(1) << (bit & 63); }
  bool test(int bit) const { return (word[bit >> 6] >> (bit & 63)) & 1; }
  int count() const { return std::popcount(word[0]) + std::popcount(word[1]); }
  /// Set bits below `bit`.
  int rank(int bit) const {
    if (bit < 64)
      return std::popcount(word[0] & ((uint64_t(1) << bit) - 1));
    return std::popcount(word[0]) + std::popcount(word[1] & ((uint64_t(1) << (bit - 64)) - 1));
  }
  template <typename F> void forEach(F &&f) const {
    for (int w = 0; w < 2; ++w)
      for (uint64_t bits = word[w]; bits; bits &= bits - 1)
        f(64 * w + std::countr_zero(bits));
  }
};

int slotOf(int a, int b, int c) { return a + 5 * b + 25 * c; }
std::array<int, 3> slotCoords(int slot) { return {slot % 5, slot / 5 % 5, slot / 25}; }

/// Index of a leaf edge along axis t whose other coordinates (0 or 4) are q[(t+1)%3], q[(t+2)%3].
int edgeIndex(int t, const int *q) { return 4 * t + (q[(t + 1) % 3] ? 1 : 0) + 2 * (q[(t + 2) % 3] ? 1 : 0); }

int directionIndex(int dx, int dy, int dz) { return (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1); }

/// Split state of a leaf: bit f (f = 2·axis + side) when the face's neighbour is finer, bit 6 + edge when a
/// finer leaf touches the edge. `levels` holds the level of the leaf at each neighbouring cube (-1: none).
uint32_t splitBits(int level, const int *levels) {
  uint32_t bits = 0;
  for (int a = 0; a < 3; ++a)
    for (int s = 0; s < 2; ++s) {
      int d[3] = {0, 0, 0};
      d[a] = s ? 1 : -1;
      if (levels[directionIndex(d[0], d[1], d[2])] > level)
        bits |= 1u << (2 * a + s);
    }
  for (int t = 0; t < 3; ++t)
    for (int p1 = 0; p1 < 2; ++p1)
      for (int p2 = 0; p2 < 2; ++p2) {
        const int u = (t + 1) % 3, v = (t + 2) % 3;
        bool split = false;
        for (int around = 1; around < 4; ++around) {
          int d[3] = {0, 0, 0};
          d[u] = (around & 1) ? (p1 ? 1 : -1) : 0;
          d[v] = (around & 2) ? (p2 ? 1 : -1) : 0;
          split |= levels[directionIndex(d[0], d[1], d[2])] > level;
        }
        if (split)
          bits |= 1u << (6 + 4 * t + p1 + 2 * p2);
      }
  return bits;
}

struct LocalTet {
  uint8_t v[4];
};

/// The tets of a leaf with the given split state, as slots of its quarter lattice, positively oriented.
int leafTets(uint32_t bits, LocalTet *out) {
  int count = 0;
  const int centre = slotOf(2, 2, 2);
  auto emit = [&](int apex, int p, int q) {
    LocalTet t{{uint8_t(centre), uint8_t(apex), uint8_t(p), uint8_t(q)}};
    const auto c = slotCoords(centre), a = slotCoords(apex), b = slotCoords(p), d = slotCoords(q);
    const int e1[3] = {a[0] - c[0], a[1] - c[1], a[2] - c[2]};
    const int e2[3] = {b[0] - c[0], b[1] - c[1], b[2] - c[2]};
    const int e3[3] = {d[0] - c[0], d[1] - c[1], d[2] - c[2]};
    const int det = e1[0] * (e2[1] * e3[2] - e2[2] * e3[1]) - e1[1] * (e2[0] * e3[2] - e2[2] * e3[0]) +
                    e1[2] * (e2[0] * e3[1] - e2[1] * e3[0]);
    if (det < 0)
      std::swap(t.v[1], t.v[2]);
    out[count++] = t;
  };
  for (int a = 0; a < 3; ++a)
    for (int s = 0; s < 2; ++s) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      auto at = [&](int u, int v) {
        int q[3];
        q[a] = 4 * s;
        q[b] = u;
        q[c] = v;
        return slotOf(q[0], q[1], q[2]);
      };
      if (bits >> (2 * a + s) & 1) {
        for (int i = 0; i < 2; ++i)
          for (int j = 0; j < 2; ++j) {
            const int loop[4] = {at(2 * i, 2 * j), at(2 * i + 2, 2 * j), at(2 * i + 2, 2 * j + 2),
                                 at(2 * i, 2 * j + 2)};
            const int apex = at(2 * i + 1, 2 * j + 1);
            for (int k = 0; k < 4; ++k)
              emit(apex, loop[k], loop[(k + 1) % 4]);
          }
        continue;
      }
      int loop[8], n = 0;
      const int corners[4][2] = {{0, 0}, {4, 0}, {4, 4}, {0, 4}};
      for (int k = 0; k < 4; ++k) {
        const int *from = corners[k], *to = corners[(k + 1) % 4];
        loop[n++] = at(from[0], from[1]);
        const int mu = (from[0] + to[0]) / 2, mv = (from[1] + to[1]) / 2;
        int q[3];
        q[a] = 4 * s;
        q[b] = mu;
        q[c] = mv;
        const int along = from[0] != to[0] ? b : c;
        if (bits >> (6 + edgeIndex(along, q)) & 1)
          loop[n++] = at(mu, mv);
      }
      const int apex = at(2, 2);
      for (int k = 0; k < n; ++k)
        emit(apex, loop[k], loop[(k + 1) % n]);
    }
  return count;
}

class TetMesher {
public:
  TetMesher(const Volume &volume, const GenOptions &options)
      : volume_(volume), options_(options), pyramid_(volume),
        threshold_(effectiveThreshold(volume, options)) {
    // The domain is the volume's box, cut into K_x × K_y × K_z root cubes of about equal physical sides (K
    // of the shortest axis is 1), stretched per axis to fit exactly; they are nodes of one virtual octree.
    double extent[3], shortest = INFINITY;
    for (int a = 0; a < 3; ++a) {
      if (volume.dims[a] < 2)
        throw Error(volume.name, "", "expected at least 2 voxels along each axis");
      const double column = std::sqrt(volume.toWorld[0][a] * volume.toWorld[0][a] +
                                      volume.toWorld[1][a] * volume.toWorld[1][a] +
                                      volume.toWorld[2][a] * volume.toWorld[2][a]);
      extent[a] = column * double(volume.dims[a] - 1);
      shortest = std::min(shortest, extent[a]);
    }
    int64_t roots[3], most = 1;
    for (int a = 0; a < 3; ++a) {
      roots[a] = std::max<int64_t>(1, std::llround(extent[a] / shortest));
      most = std::max(most, roots[a]);
    }
    int rootLevel = 0;
    while ((int64_t(1) << rootLevel) < most)
      ++rootLevel;
    if (rootLevel > 8)
      throw Error(volume.name, "", "the volume is too elongated to mesh (sides differ more than 256×)");
    cellScale_ = 1.0;
    for (int a = 0; a < 3; ++a) {
      domainUnits_[a] = roots[a] * side(rootLevel);
      voxelsPerUnit_[a] = double(volume.dims[a] - 1) / double(domainUnits_[a]);
      cellScale_ *= voxelsPerUnit_[a];
    }
    cellScale_ = std::cbrt(cellScale_);
    float lo, hi;
    pyramid_.range({0, 0, 0}, {volume.dims[0], volume.dims[1], volume.dims[2]}, lo, hi);
    valueSpan_ = double(hi) - double(lo);
  }

  Mesh run();

private:
  int64_t side(int level) const { return kRootSide >> level; }
  bool intersects(int64_t x, int64_t y, int64_t z) const {
    const int64_t p[3] = {x, y, z};
    for (int a = 0; a < 3; ++a)
      if (p[a] >= domainUnits_[a])
        return false;
    return true;
  }
  void range(int64_t x, int64_t y, int64_t z, int level, float &lo, float &hi) const {
    const int64_t p[3] = {x, y, z};
    std::array<int64_t, 3> first, last;
    for (int a = 0; a < 3; ++a) {
      first[a] = int64_t(std::floor(double(p[a]) * voxelsPerUnit_[a]));
      last[a] = int64_t(std::ceil(double(p[a] + side(level)) * voxelsPerUnit_[a]));
    }
    pyramid_.range(first, last, lo, hi);
  }
  bool splits(int64_t x, int64_t y, int64_t z, int level, float lo, float hi, double tau) const {
    if (level >= kMaxLevel || hi < threshold_)
      return false;
    if (level < coarseLevel_)
      return true;
    // Quantised values (8-bit scans) give many cubes the same indicator; a fixed factor in [0.75, 1.25)
    // per cube, from a hash of its position, breaks the ties so that the count follows τ smoothly.
    const double tieBreak =
        0.75 + 0.5 * double(mix(morton(x, y, z) ^ uint64_t(level) << 60) >> 11) * 0x1.0p-53;
    return double(hi - lo) * std::cbrt(double(side(level)) * cellScale_) * tieBreak > tau;
  }
  uint64_t estimate(float lo, float hi) const {
    return hi < threshold_
               ? 0
               : (lo >= threshold_ ? uint64_t(kTetsPerLeafGuess) : uint64_t(kTetsPerLeafGuess / 2));
  }

  template <typename Leaf>
  void refine(int64_t x, int64_t y, int64_t z, int level, double tau, Leaf &&leaf,
              const std::atomic<bool> &stop) const {
    if (!intersects(x, y, z) || stop.load(std::memory_order_relaxed))
      return;
    float lo, hi;
    range(x, y, z, level, lo, hi);
    if (!splits(x, y, z, level, lo, hi, tau)) {
      leaf(x, y, z, level, lo, hi);
      return;
    }
    const int64_t half = side(level + 1);
    for (int c = 0; c < 8; ++c)
      refine(x + (c & 1) * half, y + (c >> 1 & 1) * half, z + (c >> 2) * half, level + 1, tau, leaf, stop);
  }

  struct Node {
    int64_t x, y, z;
    int level;
    bool walk; ///< a node the parallel walk goes on from; otherwise a leaf
  };
  std::vector<Node> topNodes(double tau) const;
  void chooseCoarseLevel();
  uint64_t estimateCells(double tau, uint64_t cap) const;
  double searchTau(double goal, double start, double tauMax) const;
  bool keeps(uint64_t code, int level, const LocalTet &tet) const;
  void buildLeaves(double tau);
  void balance();
  int64_t locate(int64_t x, int64_t y, int64_t z) const;
  int64_t ownerOf(const int64_t *q) const;
  int slotIn(int64_t leaf, const int64_t *q) const;
  void neighbourLevels(int64_t leaf, int *levels) const;
  uint64_t classify();
  void number();
  Mesh emit();

  const Volume &volume_;
  const GenOptions &options_;
  RangePyramid pyramid_;
  float threshold_;
  double voxelsPerUnit_[3] = {1.0, 1.0, 1.0};
  int64_t domainUnits_[3] = {kRootSide, kRootSide, kRootSide};
  double cellScale_ = 1.0; ///< voxels per finest unit, geometric mean over the axes
  double valueSpan_ = 0.0;
  int coarseLevel_ = 0;

  // Leaves in Morton order, and what the passes learn about each.
  std::vector<uint64_t> codes_;
  std::vector<uint8_t> levels_;
  std::vector<uint32_t> bits_;
  std::vector<Mask128> used_;  ///< slots used by the leaf's kept tets
  std::vector<Mask128> owned_; ///< slots the leaf owns that some kept tet uses
  std::vector<uint32_t> kept_;
  std::vector<uint64_t> tetOffset_, vertexOffset_;
};

constexpr int kStartLevel = 3;

std::vector<TetMesher::Node> TetMesher::topNodes(double tau) const {
  std::vector<Node> nodes;
  auto visit = [&](auto &&self, int64_t x, int64_t y, int64_t z, int level) -> void {
    if (!intersects(x, y, z))
      return;
    if (level == kStartLevel) {
      nodes.push_back({x, y, z, level, true});
      return;
    }
    float lo, hi;
    range(x, y, z, level, lo, hi);
    if (!splits(x, y, z, level, lo, hi, tau)) {
      nodes.push_back({x, y, z, level, false});
      return;
    }
    const int64_t half = side(level + 1);
    for (int c = 0; c < 8; ++c)
      self(self, x + (c & 1) * half, y + (c >> 1 & 1) * half, z + (c >> 2) * half, level + 1);
  };
  visit(visit, 0, 0, 0, 0);
  return nodes;
}

void TetMesher::chooseCoarseLevel() {
  // The coarsest level is the deepest whose nodes holding values above the threshold, ~36 tets each, stay
  // under a sixteenth of the target: the rest of the budget goes to grading.
  std::vector<Node> level{{0, 0, 0, 0, false}};
  coarseLevel_ = 0;
  for (int l = 0; l + 1 < kMaxLevel; ++l) {
    // Children in fixed slots (8 per node, in order), filled in parallel, then compacted.
    std::vector<Node> slots(8 * level.size());
    tbb::parallel_for(size_t(0), level.size(), [&](size_t i) {
      const Node &n = level[i];
      const int64_t half = side(l + 1);
      for (int c = 0; c < 8; ++c) {
        Node child{n.x + (c & 1) * half, n.y + (c >> 1 & 1) * half, n.z + (c >> 2) * half, l + 1, false};
        float lo = 0, hi = -INFINITY;
        if (intersects(child.x, child.y, child.z))
          range(child.x, child.y, child.z, l + 1, lo, hi);
        child.walk = hi >= threshold_; // marks the children kept
        slots[8 * i + c] = child;
      }
    });
    std::vector<Node> next;
    for (const Node &child : slots)
      if (child.walk)
        next.push_back(child);
    if (next.empty() || double(next.size()) * kTetsPerLeafGuess > double(options_.cells) / 16.0)
      break;
    level = std::move(next);
    coarseLevel_ = l + 1;
  }
}

uint64_t TetMesher::estimateCells(double tau, uint64_t cap) const {
  // Integer sums, so that the bisection, and with it the mesh, does not depend on the order of the walks.
  const std::vector<Node> nodes = topNodes(tau);
  std::atomic<uint64_t> total{0};
  std::atomic<bool> stop{false};
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t i) {
    const Node &n = nodes[i];
    uint64_t local = 0;
    auto leaf = [&](int64_t, int64_t, int64_t, int, float lo, float hi) {
      local += estimate(lo, hi);
      if (local > 4096) {
        if (total.fetch_add(local) + local > cap)
          stop = true;
        local = 0;
      }
    };
    if (n.walk) {
      refine(n.x, n.y, n.z, n.level, tau, leaf, stop);
    } else {
      float lo, hi;
      range(n.x, n.y, n.z, n.level, lo, hi);
      leaf(n.x, n.y, n.z, n.level, lo, hi);
    }
    total.fetch_add(local);
  });
  return stop || total > cap ? 2 * cap : total.load();
}

void TetMesher::buildLeaves(double tau) {
  const std::vector<Node> nodes = topNodes(tau);
  std::vector<std::vector<std::pair<uint64_t, uint8_t>>> parts(nodes.size());
  const std::atomic<bool> never{false};
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t i) {
    const Node &n = nodes[i];
    auto leaf = [&](int64_t x, int64_t y, int64_t z, int level, float, float) {
      parts[i].emplace_back(morton(x, y, z), uint8_t(level));
    };
    if (n.walk)
      refine(n.x, n.y, n.z, n.level, tau, leaf, never);
    else
      leaf(n.x, n.y, n.z, n.level, 0.f, 0.f);
  });
  size_t count = 0;
  for (const auto &part : parts)
    count += part.size();
  codes_.clear();
  levels_.clear();
  codes_.reserve(count);
  levels_.reserve(count);
  for (auto &part : parts) {
    for (const auto &[code, level] : part) {
      codes_.push_back(code);
      levels_.push_back(level);
    }
    std::vector<std::pair<uint64_t, uint8_t>>().swap(part);
  }
}

int64_t TetMesher::locate(int64_t x, int64_t y, int64_t z) const {
  if (x < 0 || y < 0 || z < 0 || x >= kRootSide || y >= kRootSide || z >= kRootSide)
    return -1;
  const uint64_t code = morton(x, y, z);
  const auto it = std::upper_bound(codes_.begin(), codes_.end(), code);
  if (it == codes_.begin())
    return -1;
  const int64_t i = (it - codes_.begin()) - 1;
  const uint64_t span = uint64_t(1) << (3 * (kMaxLevel - levels_[i]));
  return code - codes_[i] < span ? i : -1;
}

void TetMesher::balance() {
  // Splitting a leaf only makes its neighbours' surroundings finer, so after the first sweep only the new
  // children need checking, and the leaves that asked for a split (a neighbour 3 levels coarser is still
  // too coarse after one split).
  std::vector<size_t> check(codes_.size());
  for (size_t i = 0; i < check.size(); ++i)
    check[i] = i;
  while (!check.empty()) {
    const size_t n = codes_.size();
    std::vector<std::atomic<uint8_t>> split(n), asked(n);
    std::atomic<bool> any{false};
    tbb::parallel_for(size_t(0), check.size(), [&](size_t c) {
      const size_t i = check[c];
      const int level = levels_[i];
      if (level < 2)
        return;
      const int64_t s = side(level);
      const int64_t x = compactBits3(codes_[i]), y = compactBits3(codes_[i] >> 1),
                    z = compactBits3(codes_[i] >> 2);
      for (int d = 0; d < 27; ++d) {
        if (d == 13)
          continue;
        const int64_t j = locate(x + (d % 3 - 1) * s, y + (d / 3 % 3 - 1) * s, z + (d / 9 - 1) * s);
        if (j >= 0 && levels_[j] + 1 < level) {
          split[j].store(1, std::memory_order_relaxed);
          asked[i].store(1, std::memory_order_relaxed);
          any.store(true, std::memory_order_relaxed);
        }
      }
    });
    check.clear();
    if (!any)
      return;
    std::vector<uint64_t> codes;
    std::vector<uint8_t> levels;
    codes.reserve(n + n / 4);
    levels.reserve(n + n / 4);
    for (size_t i = 0; i < n; ++i) {
      if (!split[i].load(std::memory_order_relaxed)) {
        if (asked[i].load(std::memory_order_relaxed))
          check.push_back(codes.size());
        codes.push_back(codes_[i]);
        levels.push_back(levels_[i]);
        continue;
      }
      const int64_t x = compactBits3(codes_[i]), y = compactBits3(codes_[i] >> 1),
                    z = compactBits3(codes_[i] >> 2);
      const int64_t half = side(levels_[i] + 1);
      for (int c = 0; c < 8; ++c) {
        const int64_t cx = x + (c & 1) * half, cy = y + (c >> 1 & 1) * half, cz = z + (c >> 2) * half;
        if (!intersects(cx, cy, cz))
          continue;
        check.push_back(codes.size());
        codes.push_back(morton(cx, cy, cz));
        levels.push_back(uint8_t(levels_[i] + 1));
      }
    }
    codes_ = std::move(codes);
    levels_ = std::move(levels);
  }
}

void TetMesher::neighbourLevels(int64_t leaf, int *levels) const {
  const int64_t s = side(levels_[leaf]);
  const int64_t x = compactBits3(codes_[leaf]), y = compactBits3(codes_[leaf] >> 1),
                z = compactBits3(codes_[leaf] >> 2);
  for (int d = 0; d < 27; ++d) {
    const int64_t j =
        d == 13 ? leaf : locate(x + (d % 3 - 1) * s, y + (d / 3 % 3 - 1) * s, z + (d / 9 - 1) * s);
    levels[d] = j >= 0 ? levels_[j] : -1;
  }
}

int64_t TetMesher::ownerOf(const int64_t *q) const {
  // The leaf whose half-open box holds the point; on the far sides of the domain, the first leaf around it.
  for (int octant = 0; octant < 8; ++octant) {
    int64_t cell[3];
    for (int a = 0; a < 3; ++a)
      cell[a] = (octant >> a & 1) ? (q[a] + 3) / 4 - 1 : q[a] / 4;
    const int64_t j = locate(cell[0], cell[1], cell[2]);
    if (j >= 0)
      return j;
  }
  throw Error("uvr gen: a mesh vertex lies in no octree leaf");
}

int TetMesher::slotIn(int64_t leaf, const int64_t *q) const {
  const int64_t s = side(levels_[leaf]);
  const int64_t lo[3] = {compactBits3(codes_[leaf]), compactBits3(codes_[leaf] >> 1),
                         compactBits3(codes_[leaf] >> 2)};
  int local[3];
  for (int a = 0; a < 3; ++a) {
    const int64_t offset = q[a] - 4 * lo[a];
    if (offset < 0 || offset > 4 * s || offset % s != 0)
      throw Error("uvr gen: a mesh vertex is not on its neighbour's lattice (non-conforming octree)");
    local[a] = int(offset / s);
  }
  return slotOf(local[0], local[1], local[2]);
}

/// Lattice position of a slot of a leaf, in quarters of the finest unit.
void slotPosition(uint64_t code, int level, int slot, int64_t *q) {
  const int64_t s = kRootSide >> level;
  const auto c = slotCoords(slot);
  q[0] = 4 * int64_t(compactBits3(code)) + c[0] * s;
  q[1] = 4 * int64_t(compactBits3(code >> 1)) + c[1] * s;
  q[2] = 4 * int64_t(compactBits3(code >> 2)) + c[2] * s;
}

bool TetMesher::keeps(uint64_t code, int level, const LocalTet &tet) const {
  int64_t sum[3] = {0, 0, 0};
  for (int k = 0; k < 4; ++k) {
    int64_t q[3];
    slotPosition(code, level, tet.v[k], q);
    for (int a = 0; a < 3; ++a)
      sum[a] += q[a];
  }
  return volume_.sample(double(sum[0]) * voxelsPerUnit_[0] / 16.0, double(sum[1]) * voxelsPerUnit_[1] / 16.0,
                        double(sum[2]) * voxelsPerUnit_[2] / 16.0) >= threshold_;
}

uint64_t TetMesher::classify() {
  const size_t n = codes_.size();
  bits_.assign(n, 0);
  used_.assign(n, Mask128{});
  kept_.assign(n, 0);
  Progress progress("classifying tets", n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t> &r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      int levels[27];
      neighbourLevels(int64_t(i), levels);
      bits_[i] = splitBits(levels_[i], levels);
      LocalTet tets[96];
      const int count = leafTets(bits_[i], tets);
      for (int t = 0; t < count; ++t)
        if (keeps(codes_[i], levels_[i], tets[t])) {
          ++kept_[i];
          for (int k = 0; k < 4; ++k)
            used_[i].set(tets[t].v[k]);
        }
    }
    progress.advance(r.size());
  });
  progress.finish();
  uint64_t total = 0;
  for (uint32_t k : kept_)
    total += k;
  return total;
}

void TetMesher::number() {
  const size_t n = codes_.size();
  owned_.assign(n, Mask128{});
  Progress progress("numbering vertices", n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t> &r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      LocalTet tets[96];
      const int count = leafTets(bits_[i], tets);
      Mask128 vertices;
      for (int t = 0; t < count; ++t)
        for (int k = 0; k < 4; ++k)
          vertices.set(tets[t].v[k]);
      vertices.forEach([&](int slot) {
        const auto c = slotCoords(slot);
        int64_t q[3];
        slotPosition(codes_[i], levels_[i], slot, q);
        const bool inside = c[0] < 4 && c[1] < 4 && c[2] < 4;
        if (!inside && ownerOf(q) != int64_t(i))
          return;
        if (used_[i].test(slot)) {
          owned_[i].set(slot);
          return;
        }
        if (c[0] > 0 && c[0] < 4 && c[1] > 0 && c[1] < 4 && c[2] > 0 && c[2] < 4)
          return; // no other leaf holds it
        for (int octant = 0; octant < 8; ++octant) {
          int64_t cell[3];
          for (int a = 0; a < 3; ++a)
            cell[a] = (octant >> a & 1) ? (q[a] + 3) / 4 - 1 : q[a] / 4;
          const int64_t j = locate(cell[0], cell[1], cell[2]);
          if (j >= 0 && j != int64_t(i) && used_[j].test(slotIn(j, q))) {
            owned_[i].set(slot);
            return;
          }
        }
      });
    }
    progress.advance(r.size());
  });
  progress.finish();
  tetOffset_.assign(n + 1, 0);
  vertexOffset_.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i) {
    tetOffset_[i + 1] = tetOffset_[i] + kept_[i];
    vertexOffset_[i + 1] = vertexOffset_[i] + uint64_t(owned_[i].count());
  }
}

Mesh TetMesher::emit() {
  const size_t n = codes_.size();
  const uint64_t pointCount = vertexOffset_[n], tetCount = tetOffset_[n];
  if (pointCount > uint64_t(UINT32_MAX))
    throw Error("uvr gen: more than 2^32 points; ask for fewer cells");
  Mesh mesh;
  mesh.points.resize(pointCount);
  mesh.tets.resize(4 * tetCount);
  ScalarField field{volume_.name, Centering::Point, UninitVector<float>(pointCount)};
  const bool mirrored = volume_.worldDeterminant() < 0;
  Progress progress("writing tets", n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t> &r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const uint64_t code = codes_[i];
      const int level = levels_[i];
      const double amplitude = kJitter * double(side(level)) * 4.0; // in quarter units
      owned_[i].forEach([&](int slot) {
        const uint64_t id = vertexOffset_[i] + uint64_t(owned_[i].rank(slot));
        int64_t q[3];
        slotPosition(code, level, slot, q);
        double p[3];
        for (int a = 0; a < 3; ++a) {
          const uint64_t h = mix(mix(mix(mix(options_.seed) ^ uint64_t(q[0])) ^ uint64_t(q[1])) ^
                                 (uint64_t(q[2]) << 2 | uint64_t(a)));
          const double u = double(h >> 11) * 0x1.0p-53 * 2.0 - 1.0;
          // Vertices on the volume's box stay on it.
          p[a] = std::clamp((double(q[a]) + amplitude * u) * voxelsPerUnit_[a] / 4.0, 0.0,
                            double(volume_.dims[a] - 1));
        }
        mesh.points[id] = volume_.world(p[0], p[1], p[2]);
        field.values[id] = volume_.sample(p[0], p[1], p[2]);
      });
      if (kept_[i] == 0)
        continue;
      uint32_t ids[kSlots];
      used_[i].forEach([&](int slot) {
        const auto c = slotCoords(slot);
        if (c[0] < 4 && c[1] < 4 && c[2] < 4) {
          ids[slot] = uint32_t(vertexOffset_[i] + uint64_t(owned_[i].rank(slot)));
          return;
        }
        int64_t q[3];
        slotPosition(code, level, slot, q);
        const int64_t owner = ownerOf(q);
        ids[slot] = uint32_t(vertexOffset_[owner] + uint64_t(owned_[owner].rank(slotIn(owner, q))));
      });
      LocalTet tets[96];
      const int count = leafTets(bits_[i], tets);
      uint32_t *out = mesh.tets.data() + 4 * tetOffset_[i];
      for (int t = 0; t < count; ++t) {
        if (!keeps(code, level, tets[t]))
          continue;
        for (int k = 0; k < 4; ++k)
          out[k] = ids[tets[t].v[k]];
        if (mirrored)
          std::swap(out[1], out[2]);
        out += 4;
      }
    }
    progress.advance(r.size());
  });
  progress.finish();
  mesh.fields.push_back(std::move(field));
  if (options_.cellField)
    mesh.fields.push_back(sampleCellCentroids(volume_, mesh));
  return mesh;
}

double TetMesher::searchTau(double goal, double start, double tauMax) const {
  // The estimate falls as τ grows, roughly as a power of τ: regula falsi (Illinois) on log estimate against
  // log τ, inside a bracket grown from `start`, needs far fewer walks than bisection.
  const uint64_t cap = uint64_t(goal * 4.0) + 1024;
  auto f = [&](double logTau) {
    return std::log(double(estimateCells(std::exp(logTau), cap)) + 1.0) - std::log(goal);
  };
  const double logMin = std::log(tauMax * 1e-12), logMax = std::log(tauMax);
  double a = std::max(logMin, std::log(start) - 1.0), b = std::min(logMax, std::log(start) + 1.0);
  double fa = f(a), fb = f(b);
  while (fa < 0 && a > logMin) { // too coarse at a: go finer
    b = a;
    fb = fa;
    a = std::max(logMin, a - 4.0);
    fa = f(a);
  }
  while (fb > 0 && b < logMax) { // too fine at b: go coarser
    a = b;
    fa = fb;
    b = std::min(logMax, b + 4.0);
    fb = f(b);
  }
  if (fa <= 0)
    return std::exp(a);
  if (fb >= 0)
    return std::exp(b);
  int side = 0;
  for (int step = 0; step < 60 && b - a > 1e-7; ++step) {
    const double c = (a * fb - b * fa) / (fb - fa);
    const double fc = f(c);
    if (std::fabs(fc) < 0.005)
      return std::exp(c);
    if (fc > 0) { // still too fine: the root lies above c
      a = c;
      fa = fc;
      if (side == -1)
        fb /= 2;
      side = -1;
    } else {
      b = c;
      fb = fc;
      if (side == 1)
        fa /= 2;
      side = 1;
    }
  }
  return std::exp(b);
}

Mesh TetMesher::run() {
  chooseCoarseLevel();
  const double target = double(options_.cells);
  const double tauMax = std::max(valueSpan_, 1e-30) * std::cbrt(double(kRootSide) * cellScale_) * 2.0;
  double goal = target, bestTau = 0, bestError = INFINITY, lastTau = 0;
  for (int round = 0; round < 8; ++round) {
    const double tau = searchTau(goal, lastTau > 0 ? lastTau : tauMax, tauMax);
    buildLeaves(tau);
    balance();
    lastTau = tau;
    const uint64_t exact = classify();
    if (exact == 0)
      throw Error(volume_.name, "", "no cell passes the threshold " + std::to_string(threshold_));
    const double error = std::fabs(double(exact) - target) / target;
    if (error < bestError) {
      bestError = error;
      bestTau = tau;
    }
    if (error <= 0.05)
      break;
    goal *= target / double(exact);
  }
  if (lastTau != bestTau) { // small meshes can step over the target; take the closest
    buildLeaves(bestTau);
    balance();
    classify();
  }
  number();
  return emit();
}

} // namespace

Mesh generateTetMesh(const Volume &volume, const GenOptions &options) {
  return TetMesher(volume, options).run();
}

float effectiveThreshold(const Volume &volume, const GenOptions &options) {
  return options.threshold ? *options.threshold : otsuThreshold(volume);
}

} // namespace uvr
