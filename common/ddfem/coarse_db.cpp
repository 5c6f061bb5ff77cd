#include "ddfem/coarse_db.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/errors.hpp"
#include "io/artifact.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {

std::int64_t CoarseDatabase::num_combinations() const {
  std::int64_t n = 1;
  for (int c = 0; c < 8; ++c) n *= num_materials();
  return n;
}

std::int64_t CoarseDatabase::combination_code(const BlockMaterials& ids) const {
  std::int64_t code = 0, base = 1;
  for (int c = 0; c < 8; ++c) {
    if (ids[c] < 1 || ids[c] > num_materials()) return -1;
    code += base * (ids[c] - 1);
    base *= num_materials();
  }
  return code;
}

BlockMaterials CoarseDatabase::combination_ids(std::int64_t code) const {
  BlockMaterials ids{};
  for (int c = 0; c < 8; ++c) {
    ids[c] = static_cast<int>(code % num_materials()) + 1;
    code /= num_materials();
  }
  return ids;
}

const CoarseMaterialFit* CoarseDatabase::find(const BlockMaterials& ids) const {
  const std::int64_t code = combination_code(ids);
  if (code < 0 || code >= static_cast<std::int64_t>(entry_of.size()) || entry_of[code] < 0) return nullptr;
  const CoarseMaterialFit& fit = entries[entry_of[code]];
  return fit.fitted ? &fit : nullptr;
}

std::vector<MaterialPtr> CoarseDatabase::palette() const {
  std::vector<MaterialPtr> p{nullptr};
  for (const DbMaterial& m : materials) p.push_back(std::make_shared<NeoHookean>(m.E, m.nu));
  return p;
}

void write_coarse_db(const std::string& path, const CoarseDatabase& db, const std::string& config_text,
                     const std::string& command_line, std::uint64_t seed, const std::string& executable) {
  ArtifactWriter out(path, kCoarseDbSchema, kCoarseDbSchemaVersion, executable, config_text, {}, seed);
  H5File& f = out.file();
  f.write_attribute("/", "command_line", command_line);
  f.write_attribute("/", "level", db.level);
  f.write_attribute("/", "num_orbits", db.num_orbits);
  const int n = db.num_materials();
  std::vector<double> E(n), nu(n), rho(n);
  std::string names;
  for (int i = 0; i < n; ++i) {
    E[i] = db.materials[i].E, nu[i] = db.materials[i].nu, rho[i] = db.materials[i].density;
    names += (i ? "\n" : "") + db.materials[i].name;
  }
  f.write_vector("/palette/E", E);
  f.write_vector("/palette/nu", nu);
  f.write_vector("/palette/density", rho);
  f.write_attribute("/palette", "names", names);
  f.write_attribute("/palette", "model", "neo-hookean");
  f.write_attribute("/palette", "ids", "row i is palette id i + 1; id 0 is void");

  const std::int64_t N = db.num_combinations();
  if (static_cast<std::int64_t>(db.entry_of.size()) != N || static_cast<std::int64_t>(db.orbit.size()) != N)
    throw std::invalid_argument("write_coarse_db: entry_of and orbit need one value per combination");
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic> ids(N, 8);
  for (std::int64_t c = 0; c < N; ++c) {
    const BlockMaterials b = db.combination_ids(c);
    for (int k = 0; k < 8; ++k) ids(c, k) = b[k];
  }
  const std::int64_t K = static_cast<std::int64_t>(db.entries.size());
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic> entry_ids(K, 8);
  MatX mu(K, 8), lambda(K, 8), C(K, 8), v(K, 24);
  VecX residual(K), heldout(K), heldout_energy(K), seconds(K);
  std::vector<int> fitted(K), train(K), held(K), dropped(K), attempted(K);
  for (std::int64_t e = 0; e < K; ++e) {
    const CoarseMaterialFit& fit = db.entries[e];
    if (fit.points() != 8) throw std::invalid_argument("write_coarse_db: level-1 fits have 8 points");
    for (int k = 0; k < 8; ++k) {
      entry_ids(e, k) = fit.material_ids[k];
      mu(e, k) = fit.mu[k], lambda(e, k) = fit.lambda[k], C(e, k) = fit.C[k];
      v.block<1, 3>(e, 3 * k) = fit.v[k].transpose();
    }
    residual[e] = fit.residual, heldout[e] = fit.heldout_error, heldout_energy[e] = fit.heldout_energy_error;
    seconds[e] = fit.seconds;
    fitted[e] = fit.fitted;
    train[e] = fit.samples_train, held[e] = fit.samples_heldout;
    dropped[e] = fit.samples_dropped, attempted[e] = fit.samples_attempted;
  }
  f.write_attribute("/", "compressed", int(db.compressed()));
  f.write_matrix("/combinations/ids", ids);
  f.write_vector("/combinations/orbit", db.orbit);
  f.write_vector("/combinations/entry", db.entry_of);
  f.write_attribute("/combinations", "order", "row = sum_c (id_c - 1) n^c, child c in hex8 order");
  f.write_attribute("/combinations/entry", "meaning", "row of /fit/* holding the combination's coarse material");
  f.write_matrix("/fit/ids", entry_ids);
  f.write_vector("/fit/fitted", fitted);
  f.write_matrix("/fit/mu", mu);
  f.write_matrix("/fit/lambda", lambda);
  f.write_matrix("/fit/C", C);
  f.write_matrix("/fit/v", v);
  f.write_attribute("/fit", "units", "mu, lambda, C: Pa (energy densities, Eq. 2.7 per quadrature point); v: unit");
  f.write_vector("/fit/residual", residual);
  f.write_vector("/fit/heldout_error", heldout);
  f.write_vector("/fit/heldout_energy_error", heldout_energy);
  f.write_vector("/fit/seconds", seconds);
  f.write_vector("/fit/samples_train", train);
  f.write_vector("/fit/samples_heldout", held);
  f.write_vector("/fit/samples_dropped", dropped);
  f.write_vector("/fit/samples_attempted", attempted);
  out.commit();
}

namespace {
[[noreturn]] void bad(const std::string& path, const std::string& what) {
  throw InputError(path + ": " + what);
}
}  // namespace

CoarseDatabase read_coarse_db(const std::string& path) {
  const ArtifactReader in(path, kCoarseDbSchema, kCoarseDbSchemaVersion);
  const H5File& f = in.file();
  CoarseDatabase db;
  db.level = f.read_attribute<int>("/", "level");
  if (db.level != 1) bad(path, "level " + std::to_string(db.level) + " is not supported (only level 1)");
  db.num_orbits = f.read_attribute<int>("/", "num_orbits");
  const auto E = f.read_vector<double>("/palette/E");
  const auto nu = f.read_vector<double>("/palette/nu");
  const auto rho = f.read_vector<double>("/palette/density");
  if (E.empty() || nu.size() != E.size() || rho.size() != E.size())
    bad(path, "/palette: E, nu and density must be non-empty and of equal length");
  std::vector<std::string> names;
  {
    std::istringstream is(f.read_string_attribute("/palette", "names"));
    for (std::string line; std::getline(is, line);) names.push_back(line);
  }
  for (size_t i = 0; i < E.size(); ++i) {
    if (!(E[i] > 0) || !(nu[i] > -1 && nu[i] < 0.5))
      bad(path, "/palette: material id " + std::to_string(i + 1) + " has invalid E or nu");
    db.materials.push_back({i < names.size() ? names[i] : "", E[i], nu[i], rho[i]});
  }
  const auto ids = f.read_matrix<int>("/combinations/ids");
  const std::int64_t N = db.num_combinations();
  if (ids.rows() != N || ids.cols() != 8)
    bad(path, "/combinations/ids has shape (" + std::to_string(ids.rows()) + ", " + std::to_string(ids.cols()) +
                  "), expected (" + std::to_string(N) + ", 8) for " + std::to_string(db.num_materials()) +
                  " materials");
  const auto orbit = f.read_vector<int>("/combinations/orbit");
  const auto entry_of = f.read_vector<int>("/combinations/entry");
  const auto entry_ids = f.read_matrix<int>("/fit/ids");
  const std::int64_t K = entry_ids.rows();
  const auto fitted = f.read_vector<int>("/fit/fitted");
  const MatX mu = f.read_matrix<double>("/fit/mu"), lambda = f.read_matrix<double>("/fit/lambda"),
             C = f.read_matrix<double>("/fit/C"), v = f.read_matrix<double>("/fit/v");
  const auto residual = f.read_vector<double>("/fit/residual");
  const auto heldout = f.read_vector<double>("/fit/heldout_error");
  const auto heldout_energy = f.read_vector<double>("/fit/heldout_energy_error");
  const auto train = f.read_vector<int>("/fit/samples_train");
  const auto held = f.read_vector<int>("/fit/samples_heldout");
  auto shape_ok = [&](const std::string& name, std::int64_t rows, std::int64_t cols, std::int64_t want_rows,
                      std::int64_t want_cols) {
    if (rows != want_rows || cols != want_cols)
      bad(path, name + " has " + std::to_string(rows) + " x " + std::to_string(cols) + " entries, expected " +
                    std::to_string(want_rows) + " x " + std::to_string(want_cols));
  };
  shape_ok("/combinations/orbit", orbit.size(), 1, N, 1);
  shape_ok("/combinations/entry", entry_of.size(), 1, N, 1);
  if (K < 1 || K > N) bad(path, "/fit/ids must have between 1 and " + std::to_string(N) + " rows");
  shape_ok("/fit/ids", K, entry_ids.cols(), K, 8);
  shape_ok("/fit/fitted", fitted.size(), 1, K, 1);
  shape_ok("/fit/mu", mu.rows(), mu.cols(), K, 8);
  shape_ok("/fit/lambda", lambda.rows(), lambda.cols(), K, 8);
  shape_ok("/fit/C", C.rows(), C.cols(), K, 8);
  shape_ok("/fit/v", v.rows(), v.cols(), K, 24);
  shape_ok("/fit/residual", residual.size(), 1, K, 1);
  shape_ok("/fit/heldout_error", heldout.size(), 1, K, 1);
  shape_ok("/fit/heldout_energy_error", heldout_energy.size(), 1, K, 1);
  shape_ok("/fit/samples_train", train.size(), 1, K, 1);
  shape_ok("/fit/samples_heldout", held.size(), 1, K, 1);
  for (std::int64_t c = 0; c < N; ++c) {
    BlockMaterials b;
    for (int k = 0; k < 8; ++k) b[k] = ids(c, k);
    if (b != db.combination_ids(c))
      bad(path, "/combinations/ids row " + std::to_string(c) + " is not combination " + std::to_string(c));
    if (entry_of[c] < -1 || entry_of[c] >= K)
      bad(path, "/combinations/entry row " + std::to_string(c) + " = " + std::to_string(entry_of[c]) +
                    " is outside /fit (" + std::to_string(K) + " rows)");
  }
  db.entries.resize(K);
  db.entry_of = entry_of;
  db.orbit = orbit;
  const auto pal = db.palette();
  for (std::int64_t e = 0; e < K; ++e) {
    CoarseMaterialFit& fit = db.entries[e];
    for (int k = 0; k < 8; ++k) {
      fit.material_ids[k] = entry_ids(e, k);
      if (fit.material_ids[k] < 1 || fit.material_ids[k] > db.num_materials())
        bad(path, "/fit/ids row " + std::to_string(e) + " has material id " + std::to_string(fit.material_ids[k]) +
                      " outside the palette");
    }
    fit.fitted = fitted[e] != 0;
    for (int k = 0; k < 8; ++k) {
      fit.mu[k] = mu(e, k), fit.lambda[k] = lambda(e, k), fit.C[k] = C(e, k);
      fit.v[k] = v.block<1, 3>(e, 3 * k).transpose();
      fit.mu0[k] = pal[fit.material_ids[k]]->shear_modulus();
      fit.lambda0[k] = pal[fit.material_ids[k]]->lame_lambda();
      if (fit.fitted && (!(fit.mu[k] >= 0) || !(fit.lambda[k] >= 0) || !(fit.C[k] >= 0) ||
                         std::abs(fit.v[k].norm() - 1) > 1e-6))
        bad(path, "/fit row " + std::to_string(e) + " point " + std::to_string(k) +
                      ": parameters must be >= 0 and v a unit vector");
    }
    fit.residual = residual[e], fit.heldout_error = heldout[e], fit.heldout_energy_error = heldout_energy[e];
    fit.samples_train = train[e], fit.samples_heldout = held[e];
  }
  return db;
}

void check_scene_palette(const CoarseDatabase& db, const std::string& db_path,
                         const std::vector<MaterialPtr>& scene_palette, const std::vector<int>& used_ids) {
  for (int id : used_ids) {
    if (id == 0) continue;
    std::ostringstream os;
    if (id > db.num_materials()) {
      os << db_path << ": the scene uses material id " << id << ", but the database palette has ids 1.."
         << db.num_materials();
      throw InputError(os.str());
    }
    const auto* nh = dynamic_cast<const NeoHookean*>(scene_palette.at(id).get());
    const DbMaterial& m = db.materials[id - 1];
    auto same = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b)); };
    if (!nh || !same(nh->youngs_modulus(), m.E) || !same(nh->poisson_ratio(), m.nu)) {
      os << db_path << ": scene material id " << id << " ("
         << (nh ? "Neo-Hookean E " + std::to_string(nh->youngs_modulus()) + ", nu " +
                      std::to_string(nh->poisson_ratio())
                : std::string("not Neo-Hookean"))
         << ") differs from the database's id " << id << " (Neo-Hookean E " << m.E << ", nu " << m.nu << ")";
      throw InputError(os.str());
    }
  }
}

CoarseMaterialLookup database_coarsening(const CoarseDatabase& db, CoarseMaterialLookup fallback) {
  return [&db, fallback](const ChildIds& ids) {
    BlockMaterials b;
    for (int c = 0; c < 8; ++c) b[c] = ids[c];
    if (const CoarseMaterialFit* fit = db.find(b)) return coarse_quadrature_materials(*fit);
    return fallback(ids);
  };
}

}  // namespace msfab
