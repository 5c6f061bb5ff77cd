#pragma once
// The scene msfab-simulate runs when no --config is given: a small
// heterogeneous Neo-Hookean bar (soft matrix, stiff layers), clamped at one
// end and bent by a load on the other.
namespace msfab {

inline constexpr const char* kDefaultSimulateScene = R"(
name: demo-bar
grid: {size: [4, 16, 4], voxel_size: 0.001}
materials:
  - {id: 1, name: soft, model: neo-hookean, E: 1.0e5, nu: 0.45, density: 1000}
  - {id: 2, name: stiff, model: neo-hookean, E: 1.0e7, nu: 0.45, density: 1200}
layout:
  - {fill: 1}
  - {layers: {axis: y, thickness: [0.002, 0.002], ids: [1, 2]}}
boundary:
  - {region: {face: ymin}, fix: [x, y, z]}
loads:
  - {region: {face: ymax}, force: [0.0, 0.0, -0.02]}
solver: {tolerance: 1.0e-6, load_steps: 2}
)";

}  // namespace msfab
