#include "homogenized_artifact.hpp"

#include "io/artifact.hpp"

namespace msfab {

void write_homogenized(const std::string& path, const CellInput& in, const HomogenizationResult& r,
                       const PlaneStrainResult* plane, const FiniteStrainCheck* finite_strain,
                       const std::string& config_text, const std::string& command_line, std::uint64_t seed) {
  std::vector<std::string> inputs;
  if (!in.source.empty()) inputs.push_back(in.source);
  inputs.insert(inputs.end(), in.files.begin(), in.files.end());
  ArtifactWriter out(path, kHomogenizedSchema, kHomogenizedSchemaVersion, "msfab-homogenize", config_text, inputs,
                     seed);
  H5File& f = out.file();
  f.write_attribute("/", "command_line", command_line);
  f.write_matrix("/C", r.C);
  f.write_attribute("/C", "order", "Voigt xx, yy, zz, yz, xz, xy; engineering shear strains (sigma = C eps)");
  f.write_attribute("/C", "units", "Pa (the materials' units)");
  f.write_matrix("/G", r.G);
  f.write_attribute("/G", "meaning", "harmonic displacements: strains under unit Voigt stresses, C^-1");
  f.write_vector("/volume_fraction", r.volume_fraction);
  f.write_attribute("/volume_fraction", "index", "material id; 0 = void");
  f.write_attribute("/", "pieces", r.pieces);
  f.write_attribute("/", "unknowns", static_cast<std::int64_t>(r.unknowns));
  f.write_attribute("/", "seconds", r.seconds);
  f.write_attribute("/", "solver", r.solver);
  f.write_attribute("/", "cg_iterations", r.iterations);
  f.write_attribute("/", "domain", r.octant ? "octant" : "cell");
  f.write_attribute("/", "strain_cases_solved", r.symmetric_cases ? 2 : 6);
  std::vector<std::int32_t> ids32(in.cell.ids.begin(), in.cell.ids.end());
  f.write_vector("/cell/ids", ids32);
  f.write_vector("/cell/size", std::vector<int>{in.cell.nx, in.cell.ny, in.cell.nz});
  f.write_attribute("/cell/ids", "order", "x fastest: i + nx (j + ny k)");
  f.write_attribute("/cell", "voxel_size", in.cell.voxel_size);
  const double dev = cubic_deviation(r.C);
  f.write_attribute("/", "cubic_deviation", dev);
  if (dev < kCubicTolerance) {
    const CubicModuli m = cubic_moduli(r.C);
    f.write_attribute("/C", "cubic_E", m.E);
    f.write_attribute("/C", "cubic_nu", m.nu);
    f.write_attribute("/C", "cubic_G", m.G);
    f.write_attribute("/C", "cubic_shear_ratio", m.shear_ratio);
  }
  if (plane) {
    const PlaneModuli m = plane_moduli(plane->C);
    f.write_matrix("/C2", plane->C);
    f.write_attribute("/C2", "order", "plane strain, Voigt xx, yy, xy; engineering shear");
    f.write_attribute("/C2", "Ex", m.Ex);
    f.write_attribute("/C2", "Ey", m.Ey);
    f.write_attribute("/C2", "nu_xy", m.nu_xy);
    f.write_attribute("/C2", "G", m.G);
    f.write_matrix("/G2", plane->G);
  }
  if (finite_strain) {
    const std::size_t n = finite_strain->points.size();
    MatX stretch(n, 3), nu(n, 2);
    std::vector<double> strain(n), stress(n);
    std::vector<int> shifted(n);
    for (std::size_t p = 0; p < n; ++p) {
      const UniaxialStrainPoint& q = finite_strain->points[p];
      strain[p] = q.strain, stress[p] = q.nominal_stress, shifted[p] = q.shifted_factorizations;
      stretch.row(p) = q.stretch.transpose();
      nu(p, 0) = q.nu[0], nu(p, 1) = q.nu[1];
    }
    f.write_vector("/finite_strain/strain", strain);
    f.write_attribute("/finite_strain/strain", "meaning", "engineering strain along the axis (stretch - 1)");
    f.write_matrix("/finite_strain/stretch", stretch);
    f.write_attribute("/finite_strain/stretch", "meaning", "macroscopic stretches x, y, z (lateral ones stress-free)");
    f.write_matrix("/finite_strain/nu", nu);
    f.write_attribute(
        "/finite_strain/nu", "meaning",
        "secant Poisson ratios -(lateral stretch - 1) / strain, the two lateral axes after the axis, cyclically");
    f.write_vector("/finite_strain/nominal_stress", stress);
    f.write_attribute("/finite_strain/nominal_stress", "meaning",
                      "axial first Piola-Kirchhoff stress (force per reference area)");
    f.write_vector("/finite_strain/shifted_factorizations", shifted);
    f.write_attribute("/finite_strain/shifted_factorizations", "meaning",
                      "Newton iterations whose Hessian needed a shift: a zero-energy hinge, or the structure buckled");
    f.write_attribute("/finite_strain", "axis", std::string(1, "xyz"[finite_strain->axis]));
    f.write_attribute("/finite_strain", "linear_nu",
                      std::vector<double>{finite_strain->linear_nu[0], finite_strain->linear_nu[1]});
    f.write_attribute("/finite_strain", "linear_E", finite_strain->linear_E);
  }
  out.commit();
}

}  // namespace msfab
