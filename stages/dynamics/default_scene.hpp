#pragma once
// Built-in scene of msfab-dynamics: the face-first block drop of thesis
// Fig. 4-13 (configs/dynamics/block_drop_face.yaml).
inline constexpr const char* kDefaultDynamicsScene = R"yaml(
name: block-drop-face
materials:
  - {name: rigur, E: 0.65e9, nu: 0.45, density: 1200, damping_a: 0, damping_b: 1.64e-4}
geometry:
  voxel_size: 0.005          # 2 x 2 x 2 hexahedra
  boxes:
    - {material: rigur, min: [0, 0, 0], max: [0.01, 0.01, 0.01]}
placement:
  translation: [0, 0, 0.03]  # bottom face 3 cm above the table
obstacles:
  - {type: ground, z: 0, surface: table}
friction:
  default: 0.5
simulation:
  time_step: 1.0e-4
  duration: 0.16
  impact: bbi                # complementarity | dke | bbi
  output_every: 20
)yaml";
