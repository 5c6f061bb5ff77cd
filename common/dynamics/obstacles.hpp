#pragma once
// Static obstacles of a dynamics scene: the ground (a half-space below a
// horizontal plane, z up) and axis-aligned boxes (platforms, walls). A
// contact against an obstacle is described by the plane of the face hit:
// the point x is admissible while n . x >= offset.
#include <optional>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace msfab {

struct Obstacle {
  enum class Kind { kGround, kBox };
  Kind kind = Kind::kGround;
  std::string name;                           // as in the scene, for messages and outputs
  double ground_z = 0.0;                      // kGround: the plane z = ground_z, solid below
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // kBox: solid between lo and hi
  std::string surface;                        // surface material, for the friction table
};

// The face plane of a contact: admissible side n . x >= offset.
struct ContactPlane {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
  double gap(const Vec3& x) const { return normal.dot(x) - offset; }
};

// Signed distance (positive outside, negative inside) to the obstacle's
// surface and the plane of the nearest face.
double signed_distance(const Obstacle& obstacle, const Vec3& x, ContactPlane* plane);

// Continuous collision detection of a point moving on the segment x0 -> x1
// against a static obstacle inflated by `margin`: the plane of the first face
// the segment crosses (or, if x0 already lies within the inflated obstacle,
// the face nearest to x0). Nothing when the segment stays outside.
std::optional<ContactPlane> first_contact(const Obstacle& obstacle, const Vec3& x0, const Vec3& x1, double margin);

}  // namespace msfab
