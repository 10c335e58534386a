#include "bricklayer/planner/collapse.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

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

struct Body {
  Vec c;            // centre
  double angle = 0.0;
  Vec v;
  double w = 0.0;
  double hx = 0.5, hy = 0.5;  // half extents
  double inv_mass = 1.0, inv_inertia = 1.0;
  bool awake = true;
  bool left = false;
  bool is_static = false;  // the surface
  std::array<Vec, 4> vertices;  // world, counter-clockwise from bottom-left
  std::array<Vec, 4> normals;   // world outward normal of edge i (vertices i -> i+1)

  void update_geometry() {
    const double cs = std::cos(angle), sn = std::sin(angle);
    auto world = [&](double lx, double ly) { return Vec{c.x + cs * lx - sn * ly, c.y + sn * lx + cs * ly}; };
    vertices = {world(-hx, -hy), world(hx, -hy), world(hx, hy), world(-hx, hy)};
    normals = {Vec{sn, -cs}, Vec{cs, sn}, Vec{-sn, cs}, Vec{-cs, -sn}};
  }
  bool dynamic() const { return !is_static && awake; }
  double im() const { return dynamic() ? inv_mass : 0.0; }
  double ii() const { return dynamic() ? inv_inertia : 0.0; }
};

struct Contact {
  int a = 0, b = 0;  // reference and incident body; the normal points from a to b
  Vec n;
  Vec ra, rb;
  double separation = 0.0;
  double approach = 0.0;  // normal velocity before the solve (negative: closing)
  double mass = 0.0;
  double target = 0.0;
  double impulse = 0.0;
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

// Keeps the part of segment (p[0], p[1]) with dot(normal, p) <= offset. Returns the number of points kept.
int clip(std::array<Vec, 2>& p, Vec normal, double offset) {
  const double d0 = dot(normal, p[0]) - offset, d1 = dot(normal, p[1]) - offset;
  std::array<Vec, 2> out;
  int count = 0;
  if (d0 <= 0) out[count++] = p[0];
  if (d1 <= 0) out[count++] = p[1];
  if (d0 * d1 < 0 && count < 2) out[count++] = p[0] + (d0 / (d0 - d1)) * (p[1] - p[0]);
  p = out;
  return count;
}

// Box2D-style manifold between two boxes: up to two contact points.
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
  const Vec r1 = R.vertices[face], r2 = R.vertices[(face + 1) % 4];
  const Vec t = (1.0 / std::sqrt(dot(r2 - r1, r2 - r1))) * (r2 - r1);
  if (clip(seg, -1.0 * t, -dot(t, r1)) < 2) return;
  if (clip(seg, t, dot(t, r2)) < 2) return;
  const double front = dot(n, r1);
  for (const Vec& p : seg) {
    const double s = dot(n, p) - front;
    if (s > margin) continue;
    Contact k;
    k.a = ref;
    k.b = inc;
    k.n = n;
    k.ra = p - R.c;
    k.rb = p - I.c;
    k.separation = s;
    out.push_back(k);
  }
}

Vec point_velocity(const Body& b, Vec r) { return b.v + cross(b.w, r); }

}  // namespace

double seconds_per_time_unit(double block_length_m) { return std::sqrt(block_length_m / 9.81); }

CollapsePreview simulate_collapse(const CollapseInput& input, const CollapseOptions& options) {
  const double h = input.block_height;
  if (!(h > 0) || !std::isfinite(h)) throw std::invalid_argument("simulate_collapse: block_height must be positive");
  if (!(options.dt > 0) || !(options.max_time > 0) || !(options.key_frame_interval > 0))
    throw std::invalid_argument("simulate_collapse: dt, max_time and key_frame_interval must be positive");
  const int n = static_cast<int>(input.blocks.size());
  std::vector<Body> bodies(n + 1);
  const double inertia = (1.0 + h * h) / 12.0;
  for (int i = 0; i < n; ++i) {
    const auto& in = input.blocks[i];
    if (!std::isfinite(in.x) || in.row < 0)
      throw std::invalid_argument("simulate_collapse: block " + std::to_string(i) + " has a bad row or x");
    Body& b = bodies[i];
    b.c = {in.x + 0.5, (in.row + 0.5) * h};
    b.hx = 0.5;
    b.hy = 0.5 * h;
    b.inv_mass = 1.0;
    b.inv_inertia = 1.0 / inertia;
    b.awake = in.moving;
    b.update_geometry();
  }
  Body& table = bodies[n];  // the surface: a big static box x <= edge, y <= 0
  table.is_static = true;
  table.awake = false;
  table.hx = table.hy = 50.0;
  table.c = {input.table_edge - 50.0, -50.0};
  table.update_geometry();

  const double dt = options.dt;
  const double margin = 0.02;   // contacts are found this far apart (speculative)
  const double slop = 0.002;    // penetration tolerated without correction
  const double baumgarte = 0.2;
  const double reach = std::sqrt(0.25 + 0.25 * h * h);

  CollapsePreview out;
  auto record = [&](double t) {
    out.times.push_back(t);
    std::vector<Pose> frame(n);
    for (int i = 0; i < n; ++i) frame[i] = {bodies[i].c.x, bodies[i].c.y, bodies[i].angle};
    out.frames.push_back(std::move(frame));
  };
  record(0.0);

  std::vector<Contact> contacts;
  double t = 0.0, next_frame = options.key_frame_interval, quiet_time = 0.0;
  const double rest_time = 0.3;
  while (t < options.max_time - 1e-12) {
    // Gravity on awake bodies.
    for (int i = 0; i < n; ++i)
      if (bodies[i].awake) bodies[i].v.y -= dt;

    // Contacts among bodies still in the pile (at least one of the pair awake).
    contacts.clear();
    for (int i = 0; i < n; ++i) {
      const Body& bi = bodies[i];
      if (bi.left) continue;
      for (int j = i + 1; j < n; ++j) {
        const Body& bj = bodies[j];
        if (bj.left || (!bi.awake && !bj.awake)) continue;
        if (std::abs(bi.c.x - bj.c.x) > 2 * reach + margin || std::abs(bi.c.y - bj.c.y) > 2 * reach + margin) continue;
        collide(bodies, i, j, margin, contacts);
      }
      if (bi.awake && bi.c.x - reach - margin <= input.table_edge && bi.c.y - reach - margin <= 0.0)
        collide(bodies, n, i, margin, contacts);
    }
    for (Contact& k : contacts) {
      const Body &A = bodies[k.a], &B = bodies[k.b];
      const double rna = cross(k.ra, k.n), rnb = cross(k.rb, k.n);
      const double kk = A.im() + B.im() + A.ii() * rna * rna + B.ii() * rnb * rnb;
      k.mass = kk > 0 ? 1.0 / kk : 0.0;
      k.approach = dot(point_velocity(B, k.rb) - point_velocity(A, k.ra), k.n);
      k.target = k.separation > 0 ? -k.separation / dt : baumgarte * std::max(-k.separation - slop, 0.0) / dt;
    }
    // Projected Gauss-Seidel on the normal impulses.
    for (int it = 0; it < options.iterations; ++it) {
      for (Contact& k : contacts) {
        if (k.mass == 0.0) continue;
        Body &A = bodies[k.a], &B = bodies[k.b];
        const double vn = dot(point_velocity(B, k.rb) - point_velocity(A, k.ra), k.n);
        const double next = std::max(k.impulse + (k.target - vn) * k.mass, 0.0);
        const double d = next - k.impulse;
        k.impulse = next;
        const Vec p = d * k.n;
        A.v = A.v - A.im() * p;
        A.w -= A.ii() * cross(k.ra, p);
        B.v = B.v + B.im() * p;
        B.w += B.ii() * cross(k.rb, p);
      }
    }
    // Wake sleeping blocks struck hard, or whose support below is moving.
    bool woke = false;
    for (const Contact& k : contacts) {
      const int pair[2] = {k.a, k.b};
      for (int s = 0; s < 2; ++s) {
        Body& sleeper = bodies[pair[s]];
        const Body& other = bodies[pair[1 - s]];
        if (sleeper.is_static || sleeper.awake || !other.awake) continue;
        const double up_from_other = s == 1 ? k.n.y : -k.n.y;  // normal component pointing from other to sleeper
        if (k.approach < -0.3 || up_from_other > 0.5) {
          sleeper.awake = true;
          woke = true;
        }
      }
    }
    // Integrate positions (semi-implicit Euler).
    bool all_quiet = true, any_in_pile = false;
    for (int i = 0; i < n; ++i) {
      Body& b = bodies[i];
      if (!b.awake) continue;
      b.c = b.c + dt * b.v;
      b.angle += dt * b.w;
      b.update_geometry();
      if (!b.left && b.c.y < -options.left_depth && b.c.x > input.table_edge) b.left = true;
      if (!b.left) {
        any_in_pile = true;
        if (std::abs(b.v.x) + std::abs(b.v.y) > 0.01 || std::abs(b.w) > 0.02) all_quiet = false;
      }
    }
    t += dt;
    ++out.steps;
    if (t >= next_frame - 1e-9) {
      record(t);
      next_frame += options.key_frame_interval;
    }
    quiet_time = (all_quiet && !woke) ? quiet_time + dt : 0.0;
    if (!any_in_pile || quiet_time >= rest_time) {
      out.came_to_rest = true;  // nothing left in the pile is moving
      break;
    }
  }
  if (out.times.back() < t - 1e-9) record(t);
  out.left_pile.resize(n);
  for (int i = 0; i < n; ++i) out.left_pile[i] = bodies[i].left;
  return out;
}

}  // namespace bricklayer::planner
