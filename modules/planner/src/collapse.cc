#include "bricklayer/planner/collapse.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/SparseCore>

#include "bricklayer/core/nnls.h"

namespace bricklayer::planner {
namespace {

struct Vec {
  double x = 0.0, y = 0.0;
};
Vec operator+(Vec a, Vec b) { return {a.x + b.x, a.y + b.y}; }
Vec operator-(Vec a, Vec b) { return {a.x - b.x, a.y - b.y}; }
Vec operator*(double s, Vec a) { return {s * a.x, s * a.y}; }
double dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y; }
double cross(Vec a, Vec b) { return a.x * b.y - a.y * b.x; }
Vec cross(double w, Vec r) { return {-w * r.y, w * r.x}; }

// Contacts are found this far apart (speculative), plus what the pair can move in the step.
constexpr double kMargin = 0.02;
constexpr double kSlop = 0.002;      // penetration tolerated without correction
constexpr double kBaumgarte = 0.2;   // fraction of the penetration (beyond the slop) corrected per step
constexpr double kWakeSpeed = 0.3;   // approach speed at which a moving block wakes a sleeping one it strikes
// A block that started moving (or was woken) is not put to sleep before this long: near the balance limit a
// block tips with an angular acceleration of a few hundredths, slow enough to pass for still at first.
constexpr double kMinAwake = 1.0;
constexpr double kClearance = 0.1;
// Steps are doubled while no awake block moves faster than this (block lengths per time unit, at its ends).
constexpr double kCalmSpeed = 1.0;   // a block sliding alone on the surface is this far from every other block

enum class State : uint8_t { kAsleep, kAwake, kFalling };

struct Body {
  Vec c, v;
  double angle = 0.0, w = 0.0;
  double hx = 0.5, hy = 0.5;  // half extents
  State state = State::kAsleep;
  bool is_table = false;
  bool ever_awake = false;
  bool slid_away = false;
  double awake_for = 0.0;  // time since it last woke
  double still_for = 0.0;  // time its speed has stayed below rest_speed
  double flat_for = 0.0;   // time its vertical speed and spin have stayed below rest_speed (sliding allowed)
  double expand = 0.0;     // broad phase: half the contact margin plus how far it can move in one step
  double lo_x = 0, hi_x = 0, lo_y = 0, hi_y = 0;  // bounding box of the vertices
  std::array<Vec, 4> vertices;  // world, counter-clockwise from bottom-left
  std::array<Vec, 4> normals;   // world outward normal of edge i (vertices i -> i+1)

  void update_geometry() {
    const double cs = std::cos(angle), sn = std::sin(angle);
    auto world = [&](double lx, double ly) { return Vec{c.x + cs * lx - sn * ly, c.y + sn * lx + cs * ly}; };
    vertices = {world(-hx, -hy), world(hx, -hy), world(hx, hy), world(-hx, hy)};
    normals = {Vec{sn, -cs}, Vec{cs, sn}, Vec{-sn, cs}, Vec{-cs, -sn}};
    lo_x = hi_x = vertices[0].x;
    lo_y = hi_y = vertices[0].y;
    for (const Vec& p : vertices) {
      lo_x = std::min(lo_x, p.x);
      hi_x = std::max(hi_x, p.x);
      lo_y = std::min(lo_y, p.y);
      hi_y = std::max(hi_y, p.y);
    }
  }
  bool awake() const { return state == State::kAwake; }
  bool in_pile() const { return state != State::kFalling; }
};

bool boxes_overlap(const Body& a, const Body& b, double grow) {
  return a.lo_x - grow <= b.hi_x && b.lo_x - grow <= a.hi_x && a.lo_y - grow <= b.hi_y && b.lo_y - grow <= a.hi_y;
}

struct Contact {
  int a = 0, b = 0;   // reference and incident body; the normal points from a to b
  uint64_t key = 0;   // body pair and contact feature, to find last step's impulse (warm start)
  Vec n, ra, rb;
  double separation = 0.0;
  double approach = 0.0;  // normal velocity before the solve (negative: closing)
  double rna = 0.0, rnb = 0.0;
  double ima = 0.0, iia = 0.0, imb = 0.0, iib = 0.0;  // inverse mass and inertia, 0 for static bodies
  double mass = 0.0;
  double target = 0.0;  // normal velocity the solve aims for (closes a gap or pushes out a penetration)
  double impulse = 0.0;
  int island = 0;
};

// Largest separation of b from one of a's faces, and that face.
double max_separation(const Body& a, const Body& b, int& face) {
  double best = -1e300;
  for (int i = 0; i < 4; ++i) {
    double s = 1e300;
    for (const Vec& v : b.vertices) s = std::min(s, dot(a.normals[i], v - a.vertices[i]));
    if (s > best) {
      best = s;
      face = i;
    }
  }
  return best;
}

// Keeps the part of segment (p[0], p[1]) with dot(normal, p) <= offset, and which end each point came
// from. Returns the number of points kept.
int clip(std::array<Vec, 2>& p, std::array<int, 2>& id, Vec normal, double offset) {
  const double d0 = dot(normal, p[0]) - offset, d1 = dot(normal, p[1]) - offset;
  std::array<Vec, 2> out;
  std::array<int, 2> out_id{};
  int count = 0;
  if (d0 <= 0) {
    out_id[count] = id[0];
    out[count++] = p[0];
  }
  if (d1 <= 0) {
    out_id[count] = id[1];
    out[count++] = p[1];
  }
  if (d0 * d1 < 0 && count < 2) {
    out_id[count] = d0 > 0 ? id[0] : id[1];  // the clipped end's place
    out[count++] = p[0] + (d0 / (d0 - d1)) * (p[1] - p[0]);
  }
  p = out;
  id = out_id;
  return count;
}

// Box2D-style manifold between two boxes (ia < ib): up to two contact points within `margin`.
void collide(const std::vector<Body>& bodies, int ia, int ib, double margin, std::vector<Contact>& out) {
  const Body& A = bodies[ia];
  const Body& B = bodies[ib];
  int face_a = 0, face_b = 0;
  const double sep_a = max_separation(A, B, face_a);
  if (sep_a > margin) return;
  const double sep_b = max_separation(B, A, face_b);
  if (sep_b > margin) return;
  int ref = ia, inc = ib, face = face_a;
  if (sep_b > sep_a + 1e-4) {
    ref = ib;
    inc = ia;
    face = face_b;
  }
  const Body& R = bodies[ref];
  const Body& I = bodies[inc];
  const Vec n = R.normals[face];
  int inc_face = 0;
  double most = 1e300;
  for (int i = 0; i < 4; ++i) {
    const double d = dot(I.normals[i], n);
    if (d < most) {
      most = d;
      inc_face = i;
    }
  }
  std::array<Vec, 2> seg = {I.vertices[inc_face], I.vertices[(inc_face + 1) % 4]};
  std::array<int, 2> id = {0, 1};
  const Vec r1 = R.vertices[face], r2 = R.vertices[(face + 1) % 4];
  const Vec t = (1.0 / std::sqrt(dot(r2 - r1, r2 - r1))) * (r2 - r1);
  if (clip(seg, id, -1.0 * t, -dot(t, r1)) < 2) return;
  if (clip(seg, id, t, dot(t, r2)) < 2) return;
  const double front = dot(n, r1);
  const uint64_t pair = (static_cast<uint64_t>(ia) << 40) | (static_cast<uint64_t>(ib) << 16);
  const uint64_t feature = (ref == ia ? 0x80u : 0u) | static_cast<uint64_t>(face << 4) |
                           static_cast<uint64_t>(inc_face << 2);
  for (int k = 0; k < 2; ++k) {
    const double s = dot(n, seg[k]) - front;
    if (s > margin) continue;
    Contact c;
    c.a = ref;
    c.b = inc;
    c.key = pair | feature | static_cast<uint64_t>(id[k]);
    c.n = n;
    c.ra = seg[k] - R.c;
    c.rb = seg[k] - I.c;
    c.separation = s;
    out.push_back(c);
  }
}

Vec point_velocity(const Body& b, Vec r) { return b.v + cross(b.w, r); }

void check_options(const CollapseInput& input, const CollapseOptions& o) {
  const double h = input.block_height;
  if (!(h > 0) || !std::isfinite(h)) throw std::invalid_argument("simulate_collapse: block_height must be positive");
  if (!std::isfinite(input.table_edge)) throw std::invalid_argument("simulate_collapse: table_edge must be finite");
  auto positive = [](double v) { return v > 0 && std::isfinite(v); };
  if (!positive(o.dt) || !positive(o.max_time) || !positive(o.key_frame_interval) || !positive(o.rest_speed) ||
      !positive(o.rest_slide_speed))
    throw std::invalid_argument(
        "simulate_collapse: dt, max_time, key_frame_interval, rest_speed and rest_slide_speed must be positive");
  if (o.max_time / o.dt > 1e6 || o.max_time / o.key_frame_interval > 1e5)
    throw std::invalid_argument("simulate_collapse: max_time allows more than 1e6 steps or 1e5 key frames");
  if (o.max_iterations < 1) throw std::invalid_argument("simulate_collapse: max_iterations must be at least 1");
  if (!(o.tolerance >= 0) || !(o.rest_time >= 0) || !(o.fall_depth >= 0) || !std::isfinite(o.tolerance) ||
      !std::isfinite(o.rest_time) || !std::isfinite(o.fall_depth))
    throw std::invalid_argument("simulate_collapse: tolerance, rest_time and fall_depth must be >= 0 and finite");
  for (size_t i = 0; i < input.blocks.size(); ++i)
    if (!std::isfinite(input.blocks[i].x) || input.blocks[i].row < 0)
      throw std::invalid_argument("simulate_collapse: block " + std::to_string(i) + " has a bad row or x");
}

// One preview: the bodies, the contacts of the current step and the impulses of the last one.
class Simulation {
 public:
  Simulation(const CollapseInput& input, const CollapseOptions& options)
      : options_(options), edge_(input.table_edge), n_(static_cast<int>(input.blocks.size())), bodies_(n_ + 1) {
    const double h = input.block_height;
    const double inv_inertia = 12.0 / (1.0 + h * h);
    for (int i = 0; i < n_; ++i) {
      const auto& in = input.blocks[i];
      Body& b = bodies_[i];
      b.c = {in.x + 0.5, (in.row + 0.5) * h};
      b.hx = 0.5;
      b.hy = 0.5 * h;
      b.update_geometry();
      if (in.moving) wake(b);
    }
    inv_inertia_ = inv_inertia;
    reach_ = std::sqrt(0.25 + 0.25 * h * h);
    Body& table = bodies_[n_];  // the surface: a big static box x <= edge, y <= 0
    table.is_table = true;
    table.hx = table.hy = 1e3;
    table.c = {edge_ - 1e3, -1e3};
    table.update_geometry();
    parent_.resize(n_);
    woken_.assign(n_, 0);
    island_index_.resize(n_);
  }

  CollapsePreview run() {
    const long max_ticks = std::lround(std::ceil(options_.max_time / options_.dt - 1e-9));
    long next_frame = 1;
    record(0.0);
    long tick = 0;  // time in units of options.dt
    bool ended = finished();
    while (!ended && tick < max_ticks) {
      // Double steps while everything awake is slow (a toppling column, debris settling); single steps for
      // impacts and fast falls. Double steps start on even ticks so key frames fall on step boundaries.
      const long ticks = tick % 2 == 0 && tick + 2 <= max_ticks && calm() ? 2 : 1;
      dt_ = static_cast<double>(ticks) * options_.dt;
      advance();
      if (out_.steps == 0) record_initial();
      ++out_.steps;
      tick += ticks;
      const double t = static_cast<double>(tick) * options_.dt;
      if (t >= static_cast<double>(next_frame) * options_.key_frame_interval - 1e-9) {
        record(t);
        while (static_cast<double>(next_frame) * options_.key_frame_interval <= t + 1e-9) ++next_frame;
      }
      ended = finished();
    }
    const double t_end = static_cast<double>(tick) * options_.dt;
    if (out_.times.back() < t_end) record(t_end);
    out_.came_to_rest = ended;
    out_.initial.resize(n_);  // no step at all (nothing awake): every block at rest
    out_.end.resize(n_);
    out_.left_pile.resize(n_);
    for (int i = 0; i < n_; ++i) {
      const Body& b = bodies_[i];
      BlockEnd e = BlockEnd::kUntouched;
      if (b.state == State::kFalling) e = BlockEnd::kFellOff;
      else if (b.awake()) e = BlockEnd::kMoving;
      else if (b.slid_away) e = BlockEnd::kSlidAway;
      else if (b.ever_awake) e = BlockEnd::kAtRest;
      out_.end[i] = e;
      out_.left_pile[i] = e == BlockEnd::kSlidAway || e == BlockEnd::kFellOff;
    }
    return std::move(out_);
  }

 private:
  // Nothing in the pile is awake and the falling blocks are out of the picture.
  bool finished() const {
    for (int i = 0; i < n_; ++i) {
      const Body& b = bodies_[i];
      if (b.awake() || (b.state == State::kFalling && b.hi_y > -options_.fall_depth)) return false;
    }
    return true;
  }

  // Every block starts at rest: its velocity after the first step over the step's length is its acceleration.
  void record_initial() {
    out_.initial.resize(n_);
    for (int i = 0; i < n_; ++i) {
      const Body& b = bodies_[i];
      if (b.state != State::kAsleep) out_.initial[i] = {b.v.x / dt_, b.v.y / dt_, b.w / dt_};
    }
  }

  void record(double t) {
    out_.times.push_back(t);
    std::vector<Pose> frame(n_);
    for (int i = 0; i < n_; ++i) frame[i] = {bodies_[i].c.x, bodies_[i].c.y, bodies_[i].angle};
    out_.frames.push_back(std::move(frame));
  }

  void wake(Body& b) {
    sleepers_changed_ = true;
    b.state = State::kAwake;
    b.ever_awake = true;
    b.slid_away = false;
    b.awake_for = b.still_for = b.flat_for = 0.0;
  }

  void put_to_sleep(Body& b, bool slid_away) {
    sleepers_changed_ = true;
    b.state = State::kAsleep;
    b.slid_away = slid_away;
    b.v = {};
    b.w = 0.0;
  }

  double im(const Body& b) const { return b.awake() ? 1.0 : 0.0; }
  double ii(const Body& b) const { return b.awake() ? inv_inertia_ : 0.0; }

  // No awake block moves faster than kCalmSpeed anywhere on it.
  bool calm() const {
    for (int i = 0; i < n_; ++i) {
      const Body& b = bodies_[i];
      if (b.awake() && std::abs(b.v.x) + std::abs(b.v.y) + std::abs(b.w) * reach_ > kCalmSpeed) return false;
    }
    return true;
  }

  void advance() {
    const double dt = dt_;
    awake_.clear();
    for (int i = 0; i < n_; ++i) {
      Body& b = bodies_[i];
      if (b.state == State::kAsleep) {
        b.expand = 0.5 * kMargin;
        continue;
      }
      b.v.y -= dt;  // gravity
      if (!b.awake()) continue;
      b.expand = 0.5 * kMargin + dt * (std::abs(b.v.x) + std::abs(b.v.y) + std::abs(b.w) * reach_);
      awake_.push_back(i);
    }
    find_contacts();
    wake_struck_sleepers();
    prepare_contacts();
    build_islands();
    solve();
    integrate();
    settle_islands();
  }

  // Broad phase: sleeping blocks sorted by the bottom of their boxes, rebuilt only when one falls asleep or
  // wakes; awake blocks swept against each other the same way every step. Only pairs with an awake block and
  // boxes within the pair's margin reach the narrow phase.
  void sort_sleepers() {
    sleepers_.clear();
    sleeper_extent_ = 0.0;
    for (int i = 0; i < n_; ++i) {
      const Body& b = bodies_[i];
      if (b.state != State::kAsleep) continue;
      sleepers_.push_back(i);
      sleeper_extent_ = std::max(sleeper_extent_, b.hi_y - b.lo_y);
    }
    std::sort(sleepers_.begin(), sleepers_.end(), [&](int a, int b) {
      return bodies_[a].lo_y < bodies_[b].lo_y || (bodies_[a].lo_y == bodies_[b].lo_y && a < b);
    });
    sleeper_lo_y_.resize(sleepers_.size());
    for (size_t k = 0; k < sleepers_.size(); ++k) sleeper_lo_y_[k] = bodies_[sleepers_[k]].lo_y;
    sleepers_changed_ = false;
  }

  // Contacts of awake block `a` with sleeping blocks and the surface. `also_woken`: also with blocks woken in
  // this step after `a` (they were asleep when the pairs were found).
  void add_sleeper_contacts(int a, bool also_woken) {
    const Body& A = bodies_[a];
    const double reach = A.expand + 0.5 * kMargin;
    const auto first = std::lower_bound(sleeper_lo_y_.begin(), sleeper_lo_y_.end(), A.lo_y - reach - sleeper_extent_);
    for (auto k = static_cast<size_t>(first - sleeper_lo_y_.begin()); k < sleepers_.size(); ++k) {
      if (sleeper_lo_y_[k] > A.hi_y + reach) break;
      const int b = sleepers_[k];
      const Body& B = bodies_[b];
      const bool pair_missing = B.state == State::kAsleep || (also_woken && B.awake() && woken_[b] && b > a);
      if (b != a && pair_missing && boxes_overlap(A, B, reach))
        collide(bodies_, std::min(a, b), std::max(a, b), reach, contacts_);
    }
    if (A.lo_y - reach <= 0.0 && A.lo_x - reach <= edge_) collide(bodies_, a, n_, reach, contacts_);
  }

  void find_contacts() {
    contacts_.clear();
    if (sleepers_changed_) sort_sleepers();
    for (int a : awake_) add_sleeper_contacts(a, false);
    by_height_ = awake_;
    std::sort(by_height_.begin(), by_height_.end(), [&](int a, int b) {
      const double la = bodies_[a].lo_y - bodies_[a].expand, lb = bodies_[b].lo_y - bodies_[b].expand;
      return la < lb || (la == lb && a < b);
    });
    for (size_t i = 0; i < by_height_.size(); ++i) {
      const int a = by_height_[i];
      const Body& A = bodies_[a];
      for (size_t j = i + 1; j < by_height_.size(); ++j) {
        const int b = by_height_[j];
        const Body& B = bodies_[b];
        if (B.lo_y - B.expand > A.hi_y + A.expand) break;
        const double margin = A.expand + B.expand;
        if (boxes_overlap(A, B, margin)) collide(bodies_, std::min(a, b), std::max(a, b), margin, contacts_);
      }
    }
  }

  // A sleeping block wakes when a moving block strikes it or when it rests on a moving block. Woken before
  // the solve, so the blow moves it this very step; and with its own contacts (below all, with the blocks it
  // rests on), or a blow would drive it into the block under it and wake the next one, down a whole tower.
  // Those new contacts wake nobody in this step: waking spreads one block per step.
  void wake_struck_sleepers() {
    const size_t found = contacts_.size();
    woken_list_.clear();
    for (size_t j = 0; j < found; ++j) {
      Contact& c = contacts_[j];
      const Body &A = bodies_[c.a], &B = bodies_[c.b];
      c.approach = dot(point_velocity(B, c.rb) - point_velocity(A, c.ra), c.n);
      for (int side = 0; side < 2; ++side) {
        const int sleeper_index = side == 0 ? c.a : c.b;
        Body& sleeper = bodies_[sleeper_index];
        const Body& other = side == 0 ? B : A;
        if (sleeper.is_table || sleeper.state != State::kAsleep || !other.awake()) continue;
        // Speculative contacts are found up to a step's travel apart: a block flying past must not wake one.
        const bool strikes = c.approach < -kWakeSpeed && c.separation + c.approach * dt_ <= 0.0;
        const double up_from_other = side == 1 ? c.n.y : -c.n.y;  // normal from the other body to the sleeper
        const bool rests_on_it = up_from_other > 0.5 && c.separation <= 0.5 * kMargin;
        if (strikes || rests_on_it) {
          wake(sleeper);
          // This step's gravity, which advance() gave only the blocks awake before it: without it a woken block
          // weighs nothing in the step it wakes, and the block under it, freed of its load, tips too soon.
          sleeper.v.y -= dt_;
          woken_[sleeper_index] = 1;
          woken_list_.push_back(sleeper_index);
        }
      }
    }
    for (int w : woken_list_) add_sleeper_contacts(w, true);
    for (int w : woken_list_) {
      awake_.push_back(w);
      woken_[w] = 0;
    }
    // Warm start from last step's impulse on the same feature.
    for (Contact& c : contacts_) {
      auto it = std::lower_bound(previous_.begin(), previous_.end(), std::make_pair(c.key, -1e300));
      if (it != previous_.end() && it->first == c.key) c.impulse = it->second * (dt_ / previous_dt_);
    }
  }

  void prepare_contacts() {
    const double dt = dt_;
    for (Contact& c : contacts_) {
      const Body &A = bodies_[c.a], &B = bodies_[c.b];
      c.rna = cross(c.ra, c.n);
      c.rnb = cross(c.rb, c.n);
      c.ima = im(A);
      c.iia = ii(A);
      c.imb = im(B);
      c.iib = ii(B);
      const double k = c.ima + c.imb + c.iia * c.rna * c.rna + c.iib * c.rnb * c.rnb;
      c.mass = k > 0 ? 1.0 / k : 0.0;
      c.target = c.separation > 0 ? -c.separation / dt : kBaumgarte * std::max(-c.separation - kSlop, 0.0) / dt;
    }
  }

  int find(int i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }

  // Awake bodies joined by contacts (sleeping ones and the surface do not join islands). Contacts are
  // grouped by island, islands numbered by their lowest body.
  void build_islands() {
    for (int i = 0; i < n_; ++i) parent_[i] = i;
    for (const Contact& c : contacts_) {
      if (!bodies_[c.a].awake() || !bodies_[c.b].awake()) continue;
      const int ra = find(c.a), rb = find(c.b);
      if (ra != rb) parent_[std::max(ra, rb)] = std::min(ra, rb);
    }
    islands_ = 0;
    for (int i = 0; i < n_; ++i) {
      if (!bodies_[i].awake()) continue;
      const int root = find(i);
      island_index_[i] = root == i ? islands_++ : island_index_[root];
    }
    island_start_.assign(islands_ + 1, 0);
    for (Contact& c : contacts_) {
      c.island = island_index_[bodies_[c.a].awake() ? c.a : c.b];
      ++island_start_[c.island + 1];
    }
    for (int k = 0; k < islands_; ++k) island_start_[k + 1] += island_start_[k];
    sorted_.resize(contacts_.size());
    std::vector<int>& fill = island_fill_;
    fill.assign(island_start_.begin(), island_start_.end() - 1);
    for (const Contact& c : contacts_) sorted_[fill[c.island]++] = c;
    contacts_.swap(sorted_);
  }

  struct Velocity {
    double x = 0.0, y = 0.0, w = 0.0;
  };

  void apply(const Contact& c, double d) {
    Velocity &A = vel_[c.a], &B = vel_[c.b];
    const double px = d * c.n.x, py = d * c.n.y;
    A.x -= c.ima * px;
    A.y -= c.ima * py;
    A.w -= c.iia * c.rna * d;
    B.x += c.imb * px;
    B.y += c.imb * py;
    B.w += c.iib * c.rnb * d;
  }

  // The first step's impulses of island `island`, exactly: the velocity problem (the velocities closest to the
  // free ones in the mass metric, M = diag(1, 1, I), with every contact's normal velocity at least its target)
  // is a least-distance program, min |u| subject to G u >= h with u = M^1/2 (v - v_free), G = J M^-1/2 and
  // h = target - J v_free, solved by NNLS (Lawson & Hanson, "Solving Least Squares Problems", ch. 23): with
  // E = [G^T; h^T] and f = (0, ..., 0, 1), lambda = argmin |E lambda - f| over lambda >= 0, r = E lambda - f,
  // the impulses are -lambda / r_last. From rest this is the exact annotator's QP scaled by the step (README
  // "First step"). Sets the impulses and applies them; false (nothing applied) when NNLS does not converge or
  // calls the program infeasible, which leaves the island to Gauss-Seidel.
  bool solve_exactly(int island) {
    const int begin = island_start_[island], end = island_start_[island + 1];
    const int m = end - begin;
    if (m == 0) return true;
    variable_.assign(n_ + 1, -1);
    int vars = 0;
    for (int j = begin; j < end; ++j)
      for (int body : {contacts_[j].a, contacts_[j].b})
        if (bodies_[body].awake() && variable_[body] < 0) {
          variable_[body] = vars;
          vars += 3;
        }
    const double root_inv_inertia = std::sqrt(inv_inertia_);
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(static_cast<size_t>(7 * m));
    for (int k = 0; k < m; ++k) {
      const Contact& c = contacts_[begin + k];
      double normal_velocity = 0.0;  // J v_free
      auto add = [&](int body, double sign, double rn) {
        const int v = variable_[body];
        if (v < 0) return;  // static: asleep or the surface
        entries.emplace_back(v, k, sign * c.n.x);
        entries.emplace_back(v + 1, k, sign * c.n.y);
        entries.emplace_back(v + 2, k, sign * rn * root_inv_inertia);
        normal_velocity += sign * (c.n.x * vel_[body].x + c.n.y * vel_[body].y + rn * vel_[body].w);
      };
      add(c.b, 1.0, c.rnb);
      add(c.a, -1.0, c.rna);
      entries.emplace_back(vars, k, c.target - normal_velocity);
    }
    Eigen::SparseMatrix<double> e(vars + 1, m);
    e.setFromTriplets(entries.begin(), entries.end());
    Eigen::VectorXd f = Eigen::VectorXd::Zero(vars + 1);
    f(vars) = 1.0;
    const core::NnlsResult lambda = core::solve_nnls(e, f, 20 * m + 100);
    if (!lambda.converged) return false;
    const double last = e.row(vars).dot(lambda.x) - 1.0;
    if (!(last < -1e-12)) return false;  // |r| = 0: infeasible (an interpenetrating start)
    for (int k = 0; k < m; ++k) {
      Contact& c = contacts_[begin + k];
      c.impulse = -lambda.x(k) / last;
      if (c.impulse > 0) apply(c, c.impulse);
    }
    return true;
  }

  // Projected Gauss-Seidel on the normal impulses, island by island, each until it stops changing. Works on a
  // compact copy of the velocities (sleeping blocks and the surface stay at zero). The first step is solved
  // exactly instead (solve_exactly): it decides which way the pile starts to move, and Gauss-Seidel from no
  // impulses at all would get that wrong in a few sweeps; its impulses then warm-start the next steps.
  void solve() {
    vel_.assign(n_ + 1, Velocity{});
    for (int i : awake_) vel_[i] = {bodies_[i].v.x, bodies_[i].v.y, bodies_[i].w};
    for (Contact& c : contacts_)
      if (c.impulse > 0) apply(c, c.impulse);
    const bool first = out_.steps == 0;
    for (int k = 0; k < islands_; ++k) {
      if (first && solve_exactly(k)) continue;
      const int begin = island_start_[k], end = island_start_[k + 1];
      for (int it = 0; it < options_.max_iterations; ++it) {
        double largest = 0.0;
        for (int j = begin; j < end; ++j) {
          Contact& c = contacts_[j];
          if (c.mass == 0.0) continue;
          const Velocity &A = vel_[c.a], &B = vel_[c.b];
          const double vn = (B.x - A.x) * c.n.x + (B.y - A.y) * c.n.y + B.w * c.rnb - A.w * c.rna;
          const double next = std::max(c.impulse + (c.target - vn) * c.mass, 0.0);
          const double d = next - c.impulse;
          if (d == 0.0) continue;
          c.impulse = next;
          apply(c, d);
          largest = std::max(largest, std::abs(d));
        }
        if (largest <= options_.tolerance) break;
      }
    }
    for (int i : awake_) {
      Body& b = bodies_[i];
      if (!b.awake()) continue;
      b.v = {vel_[i].x, vel_[i].y};
      b.w = vel_[i].w;
    }
    previous_.clear();
    previous_dt_ = dt_;
    for (const Contact& c : contacts_) previous_.emplace_back(c.key, c.impulse);
    std::sort(previous_.begin(), previous_.end());
  }

  void integrate() {
    const double dt = dt_, rest = options_.rest_speed;
    for (int i = 0; i < n_; ++i) {
      Body& b = bodies_[i];
      if (b.state == State::kAsleep) continue;
      b.c = b.c + dt * b.v;
      b.angle += dt * b.w;
      b.update_geometry();
      if (!b.awake()) continue;
      b.awake_for += dt;
      const bool flat = std::abs(b.v.y) <= rest && std::abs(b.w) * 0.5 <= rest;  // the ends move slower than rest
      b.flat_for = flat ? b.flat_for + dt : 0.0;
      b.still_for = flat && std::abs(b.v.x) <= options_.rest_slide_speed ? b.still_for + dt : 0.0;
      // Past the edge with its highest point below the surface: nothing in the pile can reach it any more.
      if (b.hi_y < 0.0 && b.lo_x > edge_ - kMargin) b.state = State::kFalling;
    }
  }

  // Islands that have been still long enough fall asleep; islands sliding alone on the surface stop.
  void settle_islands() {
    std::vector<IslandState>& info = island_states_;
    info.assign(islands_, IslandState{});
    on_surface_.assign(n_, 0);
    for (const Contact& c : contacts_) {
      const Body &A = bodies_[c.a], &B = bodies_[c.b];
      if (B.is_table) on_surface_[c.a] = 1;
      else if (A.is_table) on_surface_[c.b] = 1;
      else if (!A.awake() || !B.awake()) info[c.island].touches_pile = true;  // a sleeping block: part of the pile
    }
    const double rest_time = options_.rest_time - 1e-9;
    for (int i = 0; i < n_; ++i) {
      const Body& b = bodies_[i];
      if (!b.awake()) continue;
      IslandState& s = info[island_index_[i]];
      const bool settled = b.awake_for >= kMinAwake - 1e-9;
      s.still = s.still && settled && b.still_for >= rest_time;
      s.flat = s.flat && settled && b.flat_for >= rest_time;
      // Every block of a sliding island lies on the surface itself: a whole wall that lost its top is still
      // the pile, not debris that slid away from it.
      s.on_surface = s.on_surface && on_surface_[i] && b.c.x < edge_;
    }
    for (int k = 0; k < islands_; ++k) {
      const IslandState& s = info[k];
      if (s.still) {
        settle(k, false);
      } else if (s.flat && s.on_surface && !s.touches_pile && clear_of_others(k)) {
        settle(k, true);
      }
    }
  }

  bool clear_of_others(int island) const {
    for (int i = 0; i < n_; ++i) {
      const Body& b = bodies_[i];
      if (!b.awake() || island_index_[i] != island) continue;
      for (int j = 0; j < n_; ++j) {
        const Body& o = bodies_[j];
        if (j == i || !o.in_pile() || (o.awake() && island_index_[j] == island)) continue;
        if (boxes_overlap(b, o, kClearance)) return false;
      }
    }
    return true;
  }

  void settle(int island, bool slid_away) {
    for (int i = 0; i < n_; ++i)
      if (bodies_[i].awake() && island_index_[i] == island) put_to_sleep(bodies_[i], slid_away);
  }

  CollapseOptions options_;
  double edge_;
  int n_;
  std::vector<Body> bodies_;  // the blocks, then the surface
  double inv_inertia_ = 0.0, reach_ = 0.0;
  double dt_ = 0.0, previous_dt_ = 1.0;  // this step's and the last step's length
  std::vector<int> awake_, by_height_, woken_list_;
  std::vector<char> woken_;  // woken in this step (their pairs with sleeping blocks are still to be found)
  std::vector<int> sleepers_;         // sleeping blocks by the bottom of their boxes
  std::vector<double> sleeper_lo_y_;  // those bottoms
  double sleeper_extent_ = 0.0;       // the tallest sleeping block's box
  bool sleepers_changed_ = true;
  std::vector<Contact> contacts_, sorted_;
  std::vector<Velocity> vel_;
  std::vector<std::pair<uint64_t, double>> previous_;  // last step's impulses by contact key, sorted
  std::vector<int> parent_, island_index_, island_start_, island_fill_;
  std::vector<int> variable_;  // solve_exactly: each awake body's first variable, -1 for static ones
  int islands_ = 0;
  struct IslandState {
    bool still = true, flat = true, on_surface = true, touches_pile = false;
  };
  std::vector<IslandState> island_states_;
  std::vector<char> on_surface_;  // per block: touches the surface in this step
  CollapsePreview out_;
};

}  // namespace

double seconds_per_time_unit(double block_length_m) { return std::sqrt(block_length_m / 9.81); }

bool starts_awake(bool stable, double accel, double alpha) {
  constexpr double kZeroAcceleration = 1e-9;  // far below the tolerance, far above the QP's rounding
  return !stable || std::abs(accel) + 0.5 * std::abs(alpha) > kZeroAcceleration;
}

CollapsePreview simulate_collapse(const CollapseInput& input, const CollapseOptions& options) {
  check_options(input, options);
  return Simulation(input, options).run();
}

}  // namespace bricklayer::planner
