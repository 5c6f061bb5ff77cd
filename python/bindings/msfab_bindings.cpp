// The compiled half of the msfab Python package (python/msfab/native.py
// wraps it): the calls a researcher scripts, run by the same code as the
// stages (the same config readers, the same solvers), so that a result
// agrees with the executable's artifact bit for bit at the same thread
// count. Inputs come in as config text (YAML or JSON) and numpy arrays.
#include <omp.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/version.hpp"
#include "ddfem/coarse_db.hpp"
#include "fem/elastic_assembler.hpp"
#include "homog/periodic_homogenization.hpp"
#include "homogenization_options.hpp"
#include "io/config.hpp"
#include "scene/scene.hpp"
#include "solve/newton.hpp"

namespace py = pybind11;
using namespace msfab;

namespace {

// Threads for one call: OpenMP's count, as a stage's --threads sets it
// (0 keeps the current setting).
struct ThreadScope {
  int previous = omp_get_max_threads();
  explicit ThreadScope(int threads) {
    if (threads < 0) throw InputError("threads: must be >= 0 (0: the OpenMP default)");
    if (threads > 0) omp_set_num_threads(threads);
  }
  ~ThreadScope() { omp_set_num_threads(previous); }
};

template <class Matrix>
py::array_t<double> to_numpy(const Matrix& m) {
  py::array_t<double> out({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  auto view = out.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) view(r, c) = m(r, c);
  return out;
}

// A cell of voxel ids from an integer array of shape (nx, ny, nz), or
// (nx, ny) for a 2D cell; a[i, j, k] is voxel (i, j, k).
VoxelGrid cell_from_array(const py::array& ids, const std::vector<MaterialPtr>& material_by_id) {
  const char kind = ids.dtype().kind();
  if (kind != 'i' && kind != 'u' && kind != 'b')
    throw InputError("ids: expected an integer array of material ids, got dtype " + std::string(py::str(ids.dtype())));
  if (ids.ndim() != 3 && ids.ndim() != 2)
    throw InputError("ids: expected an array of shape (nx, ny, nz) or (nx, ny), got " + std::to_string(ids.ndim()) +
                     " dimensions");
  const auto a = py::array_t<std::int64_t, py::array::f_style | py::array::forcecast>::ensure(ids);
  const int nx = static_cast<int>(a.shape(0)), ny = static_cast<int>(a.shape(1));
  const int nz = a.ndim() == 3 ? static_cast<int>(a.shape(2)) : 1;
  if (nx < 1 || ny < 1 || nz < 1 || nx > 4096 || ny > 4096 || nz > 4096)
    throw InputError("ids: cell dimensions must be 1..4096");
  VoxelGrid cell(nx, ny, nz, 1.0 / nx, 0);
  const std::int64_t* data = a.data();  // Fortran order: x fastest, the grid's order
  for (std::size_t v = 0; v < cell.size(); ++v) {
    const std::int64_t id = data[v];
    if (id < 0 || id >= static_cast<std::int64_t>(material_by_id.size()) || (id > 0 && !material_by_id[id]))
      throw InputError("ids: voxel " + std::to_string(v) + " has id " + std::to_string(id) +
                       ", which is not a material of the palette (0 = void)");
    cell.ids[v] = static_cast<int>(id);
  }
  return cell;
}

// msfab-homogenize on a cell given as an array (stages/homogenize/main.cpp,
// steps 1-4): `config_text` holds `materials` and, optionally, `voxel_size`
// and the solver keys of the stage's config.
py::dict homogenize_array(const py::array& ids, const std::string& config_text, int threads) {
  ThreadScope scope(threads);
  const Config config = Config::from_string(config_text, "homogenize()");
  std::vector<MaterialPtr> material_by_id;
  read_materials(config, &material_by_id);
  HomogenizationOptions options = read_homogenization_options(config);
  VoxelGrid cell = cell_from_array(ids, material_by_id);
  cell.voxel_size = config.get_or<double>("voxel_size", cell.voxel_size);
  if (!(cell.voxel_size > 0)) config.fail("voxel_size", "must be > 0");
  config.check_no_unknown_keys();
  options.threads = threads;
  HomogenizationResult r;
  py::dict out;
  {
    py::gil_scoped_release release;
    if (cell.nz == 1) {
      const PlaneStrainResult plane = homogenize_plane_strain(cell, material_by_id, options);
      r = plane.full;
      py::gil_scoped_acquire acquire;
      out["C_plane"] = to_numpy(plane.C);
    } else {
      r = homogenize(cell, material_by_id, options);
    }
  }
  out["C"] = to_numpy(r.C);
  out["solid_fraction"] = 1.0 - r.volume_fraction[0];
  out["pieces"] = r.pieces;
  out["solver"] = r.solver;
  out["unknowns"] = r.unknowns;
  out["seconds"] = r.seconds;
  return out;
}

// msfab-simulate without coarsening (stages/simulate/main.cpp, steps 1, 2
// and 4): the scene file with `overrides` applied (as --set), solved by
// Newton. NumericalError if Newton does not converge.
py::dict simulate_scene(const std::string& config_path, const std::vector<std::string>& overrides, int threads) {
  ThreadScope scope(threads);
  Config config = Config::load_file(config_path);
  config.apply_overrides(overrides);
  const Scene scene = read_scene(config);
  config.check_no_unknown_keys();
  const VoxelMesh vm = build_voxel_mesh(scene.grid, scene.material_by_id);
  const StaticConditions conditions = build_static_conditions(scene, vm);
  NewtonResult result;
  {
    py::gil_scoped_release release;
    result = solve_static(ElasticAssembler(vm.mesh), conditions.dirichlet, conditions.force, scene.newton);
  }
  if (!result.converged)
    throw NumericalError(config_path + ": Newton did not converge: " + result.failure + "\nresidual history:\n" +
                         format_history(result.history));
  const HexMesh& mesh = vm.mesh;
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> u(mesh.num_nodes(), 3);
  for (int n = 0; n < mesh.num_nodes(); ++n)
    for (int a = 0; a < 3; ++a) u(n, a) = result.x[3 * n + a] - mesh.nodes(n, a);
  py::array_t<std::int64_t> elements({static_cast<py::ssize_t>(mesh.num_elements()), py::ssize_t(8)});
  auto e = elements.mutable_unchecked<2>();
  for (int el = 0; el < mesh.num_elements(); ++el)
    for (int c = 0; c < 8; ++c) e(el, c) = mesh.elements[el][c];
  py::dict out;
  out["nodes"] = to_numpy(mesh.nodes);
  out["elements"] = elements;
  out["displacement"] = to_numpy(u);
  out["newton_iterations"] = result.iterations;
  out["load_steps"] = result.load_steps;
  out["newton_seconds"] = result.timings.total;
  return out;
}

// A coarse material of a DDFEM database as numpy arrays (per coarse
// quadrature point: mu, lambda, C, the spring directions v).
py::dict fit_to_dict(const CoarseMaterialFit& fit) {
  py::dict out;
  const auto vector = [](const std::vector<double>& v) { return py::array_t<double>(v.size(), v.data()); };
  out["ids"] = std::vector<int>(fit.material_ids.begin(), fit.material_ids.end());
  out["mu"] = vector(fit.mu);
  out["lambda"] = vector(fit.lambda);
  out["C"] = vector(fit.C);
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> v(fit.v.size(), 3);
  for (std::size_t k = 0; k < fit.v.size(); ++k) v.row(static_cast<Eigen::Index>(k)) = fit.v[k].transpose();
  out["v"] = to_numpy(v);
  out["mu_centre"] = fit.mu_centre;
  out["lambda_centre"] = fit.lambda_centre;
  out["enhanced"] = fit.enhanced;
  out["residual"] = fit.residual;
  out["heldout_error"] = fit.heldout_error;
  out["heldout_energy_error"] = fit.heldout_energy_error;
  return out;
}

// Level-1 lookup, as msfab-simulate --coarsen 1 does it: the coarse
// material of the 2 x 2 x 2 block with children `ids` (hex8 order, child
// c = 4 i + 2 j + k at offset (i, j, k)), or None where the database has no
// fit (naive coarsening online).
py::object lookup_block(const CoarseDatabase& db, const std::vector<int>& ids) {
  if (db.level != 1)
    throw InputError("lookup: this is a level-" + std::to_string(db.level) +
                     " database, whose rows are found from the level-1 entries of a cell's children; look blocks up "
                     "in its level-1 database");
  if (ids.size() != 8)
    throw InputError("lookup: expected the 8 child ids of a 2 x 2 x 2 block, got " + std::to_string(ids.size()));
  BlockMaterials block{};
  for (int c = 0; c < 8; ++c) {
    if (ids[c] < 0 || ids[c] > db.num_materials())
      throw InputError("lookup: child " + std::to_string(c) + " has id " + std::to_string(ids[c]) +
                       ", the database's palette has ids 1.." + std::to_string(db.num_materials()) + " (0 = void)");
    block[c] = ids[c];
  }
  const CoarseMaterialFit* fit = db.find(block);
  if (!fit || !fit->fitted) return py::none();
  return fit_to_dict(*fit);
}

}  // namespace

PYBIND11_MODULE(msfab_bindings, m) {
  m.doc() = "msfab's core calls, run by the stages' own code (use them through the msfab package)";
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<NumericalError> numerical_error(m, "NumericalError", PyExc_ArithmeticError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      input_error(e.what());
    } catch (const NumericalError& e) {
      numerical_error(e.what());
    }
  });
  m.def("version", [] { return std::string(version()); });
  py::class_<CoarseDatabase, std::shared_ptr<CoarseDatabase>>(m, "CoarseDatabase")
      .def(py::init([](const std::string& path) { return std::make_shared<CoarseDatabase>(read_coarse_db(path)); }),
           py::arg("path"))
      .def_property_readonly("level", [](const CoarseDatabase& db) { return db.level; })
      .def_property_readonly("void_children", [](const CoarseDatabase& db) { return db.void_children; })
      .def_property_readonly("compressed", [](const CoarseDatabase& db) { return db.compressed(); })
      .def_property_readonly("entries", [](const CoarseDatabase& db) { return db.entries.size(); })
      .def_property_readonly("materials",
                             [](const CoarseDatabase& db) {
                               py::list out;
                               for (int i = 0; i < db.num_materials(); ++i) {
                                 py::dict m;
                                 m["id"] = i + 1;
                                 m["name"] = db.materials[i].name;
                                 m["E"] = db.materials[i].E;
                                 m["nu"] = db.materials[i].nu;
                                 m["density"] = db.materials[i].density;
                                 out.append(m);
                               }
                               return out;
                             })
      .def("lookup", &lookup_block, py::arg("ids"));
  m.def("homogenize", &homogenize_array, py::arg("ids"), py::arg("config_text"), py::arg("threads") = 1);
  m.def("simulate", &simulate_scene, py::arg("config_path"), py::arg("overrides") = std::vector<std::string>{},
        py::arg("threads") = 1);
}
