#include "dynamics/obstacles.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace msfab {

namespace {

// Faces of a box as planes with outward normals: -x, +x, -y, +y, -z, +z.
ContactPlane box_face(const Obstacle& b, int f) {
  const int axis = f / 2;
  ContactPlane p;
  p.normal = Vec3::Zero();
  if (f % 2 == 0) {
    p.normal(axis) = -1.0;
    p.offset = -b.lo(axis);
  } else {
    p.normal(axis) = 1.0;
    p.offset = b.hi(axis);
  }
  return p;
}

}  // namespace

double signed_distance(const Obstacle& o, const Vec3& x, ContactPlane* plane) {
  if (o.kind == Obstacle::Kind::kGround) {
    ContactPlane p{Vec3::UnitZ(), o.ground_z};
    if (plane) *plane = p;
    return p.gap(x);
  }
  // Outside: distance to the box; the reported plane is the face whose
  // outward gap is largest (the one a point moving straight in would cross).
  // Inside: the face nearest to x, negative distance.
  double best = -std::numeric_limits<double>::infinity();
  int best_face = 0;
  Vec3 outside = Vec3::Zero();
  for (int f = 0; f < 6; ++f) {
    const double g = box_face(o, f).gap(x);
    if (g > best) best = g, best_face = f;
    const int axis = f / 2;
    if (g > 0) outside(axis) = g;
  }
  if (plane) *plane = box_face(o, best_face);
  return best > 0 ? outside.norm() : best;
}

std::optional<ContactPlane> first_contact(const Obstacle& o, const Vec3& x0, const Vec3& x1, double margin) {
  if (o.kind == Obstacle::Kind::kGround) {
    const ContactPlane p{Vec3::UnitZ(), o.ground_z};
    if (std::min(p.gap(x0), p.gap(x1)) <= margin) return p;
    return std::nullopt;
  }
  Obstacle inflated = o;
  inflated.lo -= Vec3::Constant(margin);
  inflated.hi += Vec3::Constant(margin);
  ContactPlane nearest;
  if (signed_distance(inflated, x0, &nearest) <= 0) {
    nearest.offset -= margin;  // the real face, not the inflated one
    return nearest;
  }
  // Slab clipping of the segment against the inflated box: the entry time is
  // the largest per-axis entry; the face entered belongs to that axis.
  double t_in = 0.0, t_out = 1.0;
  int entry_face = -1;
  const Vec3 d = x1 - x0;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d(a)) < 1e-300) {
      if (x0(a) < inflated.lo(a) || x0(a) > inflated.hi(a)) return std::nullopt;
      continue;
    }
    double t0 = (inflated.lo(a) - x0(a)) / d(a), t1 = (inflated.hi(a) - x0(a)) / d(a);
    int f0 = 2 * a, f1 = 2 * a + 1;
    if (t0 > t1) std::swap(t0, t1), std::swap(f0, f1);
    if (t0 > t_in) t_in = t0, entry_face = f0;
    t_out = std::min(t_out, t1);
    if (t_in > t_out) return std::nullopt;
  }
  if (entry_face < 0) return std::nullopt;
  return box_face(o, entry_face);
}

}  // namespace msfab
