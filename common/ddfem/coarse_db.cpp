#include "ddfem/coarse_db.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/errors.hpp"
#include "ddfem/level2_block.hpp"
#include "io/artifact.hpp"
#include "io/field_table.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {

std::int64_t CoarseDatabase::num_combinations() const {
  std::int64_t n = 1;
  for (int c = 0; c < 8; ++c) n *= digits();
  return n;
}

std::int64_t CoarseDatabase::combination_code(const BlockMaterials& ids) const {
  const int lowest = void_children ? 0 : 1;
  std::int64_t code = 0, base = 1;
  for (int c = 0; c < 8; ++c) {
    if (ids[c] < lowest || ids[c] > num_materials()) return -1;
    code += base * (ids[c] - lowest);
    base *= digits();
  }
  return code;
}

BlockMaterials CoarseDatabase::combination_ids(std::int64_t code) const {
  const int lowest = void_children ? 0 : 1;
  BlockMaterials ids{};
  for (int c = 0; c < 8; ++c) {
    ids[c] = static_cast<int>(code % digits()) + lowest;
    code /= digits();
  }
  return ids;
}

const CoarseMaterialFit& CoarseDatabase::find_level2(const Arrangement& level1_entries) const {
  if (level != 2) throw std::logic_error("CoarseDatabase::find_level2 on a level-1 database");
  return entries.at(hierarchy.lookup(level1_entries));
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

namespace {

[[noreturn]] void bad(const std::string& path, const std::string& what) { throw InputError(path + ": " + what); }

void write_palette(H5File& f, const CoarseDatabase& db) {
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
}

// The fit's statistics, one dataset each under `<prefix>/fit`.
using Fit = CoarseMaterialFit;
const FieldOf<Fit> kFitStatistics[] = {
    MSFAB_FIELD(Fit, residual),        MSFAB_FIELD(Fit, heldout_error),    MSFAB_FIELD(Fit, heldout_energy_error),
    MSFAB_FIELD(Fit, seconds),         MSFAB_FIELD(Fit, samples_train),    MSFAB_FIELD(Fit, samples_heldout),
    MSFAB_FIELD(Fit, samples_dropped), MSFAB_FIELD(Fit, samples_attempted)};

// `<prefix>/fit/*`: one row per entry, one column per quadrature point.
void write_fits(H5File& f, const std::string& prefix, const std::vector<CoarseMaterialFit>& entries) {
  const std::int64_t K = static_cast<std::int64_t>(entries.size());
  const int P = K > 0 ? entries[0].points() : 8;
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic> entry_ids(K, 8);
  MatX mu(K, P), lambda(K, P), C(K, P), v(K, 3 * P);
  MatX centre(K, 2);
  std::vector<int> fitted(K);
  // One element for the whole database; unfitted entries carry no parameters.
  bool enhanced = false;
  for (const CoarseMaterialFit& fit : entries) enhanced = enhanced || (fit.fitted && fit.enhanced);
  for (std::int64_t e = 0; e < K; ++e) {
    const CoarseMaterialFit& fit = entries[e];
    if (fit.points() != P) throw std::invalid_argument("write_coarse_db: entries differ in their point count");
    if (fit.fitted && fit.enhanced != enhanced)
      throw std::invalid_argument("write_coarse_db: entries were fitted for different elements");
    for (int k = 0; k < 8; ++k) entry_ids(e, k) = fit.material_ids[k];
    for (int k = 0; k < P; ++k) {
      mu(e, k) = fit.mu[k], lambda(e, k) = fit.lambda[k], C(e, k) = fit.C[k];
      v.block<1, 3>(e, 3 * k) = fit.v[k].transpose();
    }
    centre(e, 0) = fit.mu_centre, centre(e, 1) = fit.lambda_centre;
    fitted[e] = fit.fitted;
  }
  const std::string g = prefix + "/fit";
  f.write_matrix(g + "/ids", entry_ids);
  f.write_vector(g + "/fitted", fitted);
  f.write_matrix(g + "/mu", mu);
  f.write_matrix(g + "/lambda", lambda);
  f.write_matrix(g + "/C", C);
  f.write_matrix(g + "/v", v);
  // Only databases fitted with the centre point carry it; without the
  // dataset mu_c = lambda_c = 0, so older databases read unchanged.
  if (centre.size() > 0 && centre.maxCoeff() > 0.0) f.write_matrix(g + "/centre", centre);
  f.write_attribute(g, "units",
                    "mu, lambda, C: Pa (energy densities, Eq. 2.7 per quadrature point); v: unit; "
                    "centre: mu_c, lambda_c in Pa (Neo-Hookean term at the element centre)");
  f.write_attribute(g, "points", P);
  // The element the fits are for; databases without the attribute are trilinear.
  f.write_attribute(g, "element", std::string(enhanced ? "enhanced" : "trilinear"));
  write_column_fields(f, g, entries, kFitStatistics);
}

// A level-1 database's combinations and fits under `prefix`.
void write_level1(H5File& f, const std::string& prefix, const CoarseDatabase& db) {
  const std::int64_t N = db.num_combinations();
  if (static_cast<std::int64_t>(db.entry_of.size()) != N || static_cast<std::int64_t>(db.orbit.size()) != N)
    throw std::invalid_argument("write_coarse_db: entry_of and orbit need one value per combination");
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic> ids(N, 8);
  for (std::int64_t c = 0; c < N; ++c) {
    const BlockMaterials b = db.combination_ids(c);
    for (int k = 0; k < 8; ++k) ids(c, k) = b[k];
  }
  for (const CoarseMaterialFit& fit : db.entries)
    if (fit.points() != 8) throw std::invalid_argument("write_coarse_db: level-1 fits have 8 points");
  const std::string g = prefix + "/combinations";
  f.write_matrix(g + "/ids", ids);
  f.write_vector(g + "/orbit", db.orbit);
  f.write_vector(g + "/entry", db.entry_of);
  f.write_attribute(g, "void_children", int(db.void_children));
  f.write_attribute(g, "order",
                    db.void_children
                        ? "row = sum_c id_c (n + 1)^c, child c in hex8 order (id 0 void; row 0, all void, has entry -1)"
                        : "row = sum_c (id_c - 1) n^c, child c in hex8 order");
  f.write_attribute(g + "/entry", "meaning", "row of " + prefix + "/fit/* holding the combination's coarse material");
  write_fits(f, prefix, db.entries);
}

void write_hierarchy(H5File& f, const Level2Hierarchy& h) {
  for (int s = 0; s < 3; ++s) {
    const PairStage& stage = h.stages[s];
    const std::string g = "/hierarchy/stage" + std::to_string(s);
    Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic> pairs(stage.outputs(), 2);
    for (int r = 0; r < stage.outputs(); ++r) pairs(r, 0) = stage.pairs[r][0], pairs(r, 1) = stage.pairs[r][1];
    f.write_vector(g + "/table", stage.table);
    f.write_matrix(g + "/pairs", pairs);
    f.write_attribute(g, "axis", std::string(1, "xyz"[s]));
    f.write_attribute(g, "inputs", stage.inputs);
    f.write_attribute(g, "mean_distance", stage.mean_distance);
    f.write_attribute(g, "max_distance", stage.max_distance);
  }
  f.write_attribute("/hierarchy", "void_input", int(h.void_input));
  f.write_attribute("/hierarchy", "meaning",
                    "stage s pairs its inputs along axis s: table[a * inputs + b] = representative of (a, b), b on "
                    "the +axis side; pairs[r] = (a, b) of representative r. Stage-0 inputs are rows of "
                    "/level1/fit; stage-2 representatives are rows of /fit");
}

}  // namespace

void write_coarse_db(const std::string& path, const CoarseDatabase& db, const std::string& config_text,
                     const std::string& command_line, std::uint64_t seed, const std::string& executable) {
  ArtifactWriter out(path, kCoarseDbSchema, kCoarseDbSchemaVersion, executable, config_text, {}, seed);
  H5File& f = out.file();
  f.write_attribute("/", "command_line", command_line);
  f.write_attribute("/", "level", db.level);
  write_palette(f, db);
  if (db.level == 1) {
    f.write_attribute("/", "num_orbits", db.num_orbits);
    f.write_attribute("/", "compressed", int(db.compressed()));
    write_level1(f, "", db);
  } else {
    if (!db.level1 || db.hierarchy.num_final() != static_cast<int>(db.entries.size()))
      throw std::invalid_argument("write_coarse_db: a level-2 database needs its level-1 database and hierarchy");
    f.write_attribute("/", "num_orbits", db.level1->num_orbits);
    f.write_attribute("/", "compressed", 1);
    write_level1(f, "/level1", *db.level1);
    write_hierarchy(f, db.hierarchy);
    write_fits(f, "", db.entries);
  }
  out.commit();
}

namespace {

void read_palette(const H5File& f, const std::string& path, CoarseDatabase& db) {
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
}

void shape_ok(const std::string& path, const std::string& name, std::int64_t rows, std::int64_t cols,
              std::int64_t want_rows, std::int64_t want_cols) {
  if (rows != want_rows || cols != want_cols)
    bad(path, name + " has " + std::to_string(rows) + " x " + std::to_string(cols) + " entries, expected " +
                  std::to_string(want_rows) + " x " + std::to_string(want_cols));
}

// `<prefix>/fit/*` with P points per entry; material ids must be in
// [min_id, max_id]. mu0 / lambda0 are left for the caller (they come from
// the palette).
std::vector<CoarseMaterialFit> read_fits(const H5File& f, const std::string& path, const std::string& prefix, int P,
                                         int min_id, int max_id, std::int64_t max_rows) {
  const std::string g = prefix + "/fit";
  const auto entry_ids = f.read_matrix<int>(g + "/ids");
  const std::int64_t K = entry_ids.rows();
  if (K < 1 || K > max_rows) bad(path, g + "/ids must have between 1 and " + std::to_string(max_rows) + " rows");
  const auto fitted = f.read_vector<int>(g + "/fitted");
  const MatX mu = f.read_matrix<double>(g + "/mu"), lambda = f.read_matrix<double>(g + "/lambda"),
             C = f.read_matrix<double>(g + "/C"), v = f.read_matrix<double>(g + "/v");
  const auto residual = f.read_vector<double>(g + "/residual");
  const auto heldout = f.read_vector<double>(g + "/heldout_error");
  const auto heldout_energy = f.read_vector<double>(g + "/heldout_energy_error");
  const auto train = f.read_vector<int>(g + "/samples_train");
  const auto held = f.read_vector<int>(g + "/samples_heldout");
  MatX centre = MatX::Zero(K, 2);
  if (f.exists(g + "/centre")) {
    centre = f.read_matrix<double>(g + "/centre");
    shape_ok(path, g + "/centre", centre.rows(), centre.cols(), K, 2);
  }
  shape_ok(path, g + "/ids", K, entry_ids.cols(), K, 8);
  shape_ok(path, g + "/fitted", fitted.size(), 1, K, 1);
  shape_ok(path, g + "/mu", mu.rows(), mu.cols(), K, P);
  shape_ok(path, g + "/lambda", lambda.rows(), lambda.cols(), K, P);
  shape_ok(path, g + "/C", C.rows(), C.cols(), K, P);
  shape_ok(path, g + "/v", v.rows(), v.cols(), K, 3 * P);
  shape_ok(path, g + "/residual", residual.size(), 1, K, 1);
  shape_ok(path, g + "/heldout_error", heldout.size(), 1, K, 1);
  shape_ok(path, g + "/heldout_energy_error", heldout_energy.size(), 1, K, 1);
  shape_ok(path, g + "/samples_train", train.size(), 1, K, 1);
  shape_ok(path, g + "/samples_heldout", held.size(), 1, K, 1);
  std::string element = "trilinear";
  if (f.has_attribute(g, "element")) element = f.read_string_attribute(g, "element");
  if (element != "trilinear" && element != "enhanced")
    bad(path, g + " attribute element is '" + element + "', expected trilinear or enhanced");
  std::vector<CoarseMaterialFit> entries(K, CoarseMaterialFit(P));
  for (std::int64_t e = 0; e < K; ++e) {
    CoarseMaterialFit& fit = entries[e];
    fit.enhanced = element == "enhanced";
    for (int k = 0; k < 8; ++k) {
      fit.material_ids[k] = entry_ids(e, k);
      if (fit.material_ids[k] < min_id || fit.material_ids[k] > max_id)
        bad(path, g + "/ids row " + std::to_string(e) + " has id " + std::to_string(fit.material_ids[k]) + " outside " +
                      std::to_string(min_id) + ".." + std::to_string(max_id));
    }
    fit.fitted = fitted[e] != 0;
    for (int k = 0; k < P; ++k) {
      fit.mu[k] = mu(e, k), fit.lambda[k] = lambda(e, k), fit.C[k] = C(e, k);
      fit.v[k] = v.block<1, 3>(e, 3 * k).transpose();
      if (fit.fitted &&
          (!(fit.mu[k] >= 0) || !(fit.lambda[k] >= 0) || !(fit.C[k] >= 0) || std::abs(fit.v[k].norm() - 1) > 1e-6))
        bad(path, g + " row " + std::to_string(e) + " point " + std::to_string(k) +
                      ": parameters must be >= 0 and v a unit vector");
    }
    fit.mu_centre = centre(e, 0), fit.lambda_centre = centre(e, 1);
    if (!(fit.mu_centre >= 0.0) || !std::isfinite(fit.mu_centre) || !(fit.lambda_centre >= 0.0) ||
        !std::isfinite(fit.lambda_centre))
      bad(path, g + "/centre row " + std::to_string(e) + " must be finite and >= 0");
    fit.residual = residual[e], fit.heldout_error = heldout[e], fit.heldout_energy_error = heldout_energy[e];
    fit.samples_train = train[e], fit.samples_heldout = held[e];
  }
  return entries;
}

// A level-1 database under `prefix`; the palette must already be in `db`.
void read_level1(const H5File& f, const std::string& path, const std::string& prefix, CoarseDatabase& db) {
  const std::string g = prefix + "/combinations";
  // Databases written before void children could be fitted have no attribute.
  db.void_children = f.has_attribute(g, "void_children") && f.read_attribute<int>(g, "void_children") != 0;
  const auto ids = f.read_matrix<int>(g + "/ids");
  const std::int64_t N = db.num_combinations();
  if (ids.rows() != N || ids.cols() != 8)
    bad(path, g + "/ids has shape (" + std::to_string(ids.rows()) + ", " + std::to_string(ids.cols()) +
                  "), expected (" + std::to_string(N) + ", 8) for " + std::to_string(db.num_materials()) +
                  " materials");
  db.orbit = f.read_vector<int>(g + "/orbit");
  db.entry_of = f.read_vector<int>(g + "/entry");
  shape_ok(path, g + "/orbit", db.orbit.size(), 1, N, 1);
  shape_ok(path, g + "/entry", db.entry_of.size(), 1, N, 1);
  db.entries = read_fits(f, path, prefix, 8, db.void_children ? 0 : 1, db.num_materials(), N);
  const std::int64_t K = static_cast<std::int64_t>(db.entries.size());
  for (std::int64_t c = 0; c < N; ++c) {
    BlockMaterials b;
    for (int k = 0; k < 8; ++k) b[k] = ids(c, k);
    if (b != db.combination_ids(c))
      bad(path, g + "/ids row " + std::to_string(c) + " is not combination " + std::to_string(c));
    if (db.entry_of[c] < -1 || db.entry_of[c] >= K)
      bad(path, g + "/entry row " + std::to_string(c) + " = " + std::to_string(db.entry_of[c]) + " is outside " +
                    prefix + "/fit (" + std::to_string(K) + " rows)");
  }
  const auto pal = db.palette();
  for (CoarseMaterialFit& fit : db.entries)
    for (int k = 0; k < 8; ++k) {
      const MaterialPtr& m = pal[fit.material_ids[k]];  // null for a void child
      fit.mu0[k] = m ? m->shear_modulus() : 0.0;
      fit.lambda0[k] = m ? m->lame_lambda() : 0.0;
    }
}

Level2Hierarchy read_hierarchy(const H5File& f, const std::string& path, int level1_entries) {
  Level2Hierarchy h;
  // Written before the all-void child could be an input: absent, 0.
  h.void_input = f.has_attribute("/hierarchy", "void_input") && f.read_attribute<int>("/hierarchy", "void_input") != 0;
  int inputs = level1_entries + (h.void_input ? 1 : 0);
  for (int s = 0; s < 3; ++s) {
    PairStage& stage = h.stages[s];
    const std::string g = "/hierarchy/stage" + std::to_string(s);
    stage.inputs = f.read_attribute<int>(g, "inputs");
    if (stage.inputs != inputs)
      bad(path, g + ": inputs = " + std::to_string(stage.inputs) + ", expected " + std::to_string(inputs) +
                    " (the previous stage's representatives)");
    stage.table = f.read_vector<int>(g + "/table");
    const auto pairs = f.read_matrix<int>(g + "/pairs");
    shape_ok(path, g + "/table", stage.table.size(), 1, std::int64_t(inputs) * inputs, 1);
    if (pairs.rows() < 1 || pairs.cols() != 2) bad(path, g + "/pairs must have at least one row of 2 columns");
    for (int r = 0; r < pairs.rows(); ++r) {
      if (pairs(r, 0) < 0 || pairs(r, 0) >= inputs || pairs(r, 1) < 0 || pairs(r, 1) >= inputs)
        bad(path, g + "/pairs row " + std::to_string(r) + " names an input outside 0.." + std::to_string(inputs - 1));
      stage.pairs.push_back({pairs(r, 0), pairs(r, 1)});
    }
    for (std::size_t i = 0; i < stage.table.size(); ++i)
      if (stage.table[i] < 0 || stage.table[i] >= stage.outputs())
        bad(path, g + "/table row " + std::to_string(i) + " = " + std::to_string(stage.table[i]) +
                      " is not a representative");
    stage.mean_distance = f.read_attribute<double>(g, "mean_distance");
    stage.max_distance = f.read_attribute<double>(g, "max_distance");
    inputs = stage.outputs();
  }
  return h;
}

}  // namespace

CoarseDatabase read_coarse_db(const std::string& path) {
  const ArtifactReader in(path, kCoarseDbSchema, kCoarseDbSchemaVersion);
  const H5File& f = in.file();
  CoarseDatabase db;
  db.level = f.read_attribute<int>("/", "level");
  if (db.level != 1 && db.level != 2) bad(path, "level " + std::to_string(db.level) + " is not 1 or 2");
  db.num_orbits = f.read_attribute<int>("/", "num_orbits");
  read_palette(f, path, db);
  if (db.level == 1) {
    read_level1(f, path, "", db);
    return db;
  }
  auto level1 = std::make_shared<CoarseDatabase>();
  level1->level = 1;
  level1->materials = db.materials;
  level1->num_orbits = db.num_orbits;
  read_level1(f, path, "/level1", *level1);
  db.hierarchy = read_hierarchy(f, path, static_cast<int>(level1->entries.size()));
  const int K = db.hierarchy.num_final();
  if (db.hierarchy.void_input && !level1->void_children)
    bad(path, "/hierarchy has a void input, but /level1 has no void children");
  db.entries = read_fits(f, path, "", 64, db.hierarchy.void_input ? 0 : 1, static_cast<int>(level1->entries.size()), K);
  if (static_cast<int>(db.entries.size()) != K)
    bad(path, "/fit has " + std::to_string(db.entries.size()) + " rows, expected one per final representative (" +
                  std::to_string(K) + ")");
  for (int r = 0; r < K; ++r) {
    CoarseMaterialFit& fit = db.entries[r];
    const Arrangement arr = db.hierarchy.arrangement(2, r);
    const int void_entry = db.hierarchy.void_entry();
    for (int c = 0; c < 8; ++c)
      if (fit.material_ids[c] != (arr[c] == void_entry ? 0 : arr[c] + 1))
        bad(path, "/fit/ids row " + std::to_string(r) + " does not match the arrangement of representative " +
                      std::to_string(r) + " in /hierarchy");
    for (int q = 0; q < 64; ++q) {
      int child = 0;
      const int k = level1_point_of(q, &child);
      const bool is_void = arr[child] == void_entry;
      fit.mu0[q] = is_void ? 0.0 : level1->entries[arr[child]].mu0[k];
      fit.lambda0[q] = is_void ? 0.0 : level1->entries[arr[child]].lambda0[k];
    }
  }
  db.level1 = level1;
  return db;
}

namespace {

// Palettes agree to a relative 1e-9 in E and nu (values written and read
// back through HDF5 and YAML).
bool same_elastic_constants(const DbMaterial& m, double E, double nu) {
  auto same = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b)); };
  return same(m.E, E) && same(m.nu, nu);
}

}  // namespace

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
    if (!nh || !same_elastic_constants(m, nh->youngs_modulus(), nh->poisson_ratio())) {
      os << db_path << ": scene material id " << id << " ("
         << (nh ? "Neo-Hookean E " + std::to_string(nh->youngs_modulus()) + ", nu " +
                      std::to_string(nh->poisson_ratio())
                : std::string("not Neo-Hookean"))
         << ") differs from the database's id " << id << " (Neo-Hookean E " << m.E << ", nu " << m.nu << ")";
      throw InputError(os.str());
    }
  }
}

void check_level1_substitute(const CoarseDatabase& substitute, const std::string& substitute_path,
                             const CoarseDatabase& level2, const std::string& level2_path) {
  const std::string both = substitute_path + " (level-1 database) and " + level2_path + " (level-2 database): ";
  if (substitute.level != 1)
    throw InputError(substitute_path + ": level: a level-" + std::to_string(substitute.level) +
                     " database cannot stand in for a level-1 base");
  if (level2.level != 2 || !level2.level1) throw InputError(level2_path + ": level: not a level-2 database");
  const CoarseDatabase& base = *level2.level1;
  if (substitute.num_materials() != base.num_materials())
    throw InputError(both + "materials: " + std::to_string(substitute.num_materials()) + " against " +
                     std::to_string(base.num_materials()) + " in the level-2 database's base");
  for (int i = 0; i < base.num_materials(); ++i) {
    const DbMaterial &a = substitute.materials[i], &b = base.materials[i];
    if (!same_elastic_constants(a, b.E, b.nu)) {
      std::ostringstream os;
      os << both << "materials: id " << i + 1 << " is E " << a.E << ", nu " << a.nu << " in the first and E " << b.E
         << ", nu " << b.nu << " in the second's base";
      throw InputError(os.str());
    }
  }
  if (substitute.void_children != base.void_children)
    throw InputError(both + "void_children: " + (substitute.void_children ? "true" : "false") + " against " +
                     (base.void_children ? "true" : "false") + " in the level-2 database's base");
  if (substitute.enhanced_element() != base.enhanced_element())
    throw InputError(
        both + "element: fitted for the " + std::string(substitute.enhanced_element() ? "enhanced" : "trilinear") +
        " coarse element, the level-2 database's base for the " + (base.enhanced_element() ? "enhanced" : "trilinear"));
}

CoarseMaterialLookup database_coarsening(const CoarseDatabase& db, CoarseMaterialLookup fallback) {
  return [&db, fallback](const ChildIds& ids) {
    BlockMaterials b;
    for (int c = 0; c < 8; ++c) b[c] = ids[c];
    if (const CoarseMaterialFit* fit = db.find(b)) return coarse_quadrature_materials(*fit);
    return fallback(ids);
  };
}

const CoarseMaterialFit* find_level2_fit(const CoarseDatabase& db, const std::vector<ChildIds>& level1_combinations,
                                         const ChildIds& ids) {
  Arrangement entries;
  for (int c = 0; c < 8; ++c) {
    if (ids[c] == 0) {  // an all-void level-1 child
      if (!db.hierarchy.void_input) return nullptr;
      entries[c] = db.hierarchy.void_entry();
      continue;
    }
    const std::array<int, 8>& fine = level1_combinations.at(ids[c] - 1);
    const std::int64_t code = db.level1->combination_code(fine);
    // A child the level-1 database holds no fit for (a void voxel in a
    // database without void children).
    if (code < 0 || db.level1->entry_of[code] < 0) return nullptr;
    entries[c] = db.level1->entry_of[code];
  }
  const CoarseMaterialFit& fit = db.find_level2(entries);
  return fit.fitted ? &fit : nullptr;
}

CoarseMaterialLookup database_coarsening_level2(const CoarseDatabase& db, const CoarseGrid& level1_grid,
                                                CoarseMaterialLookup fallback) {
  if (db.level != 2 || !db.level1) throw std::invalid_argument("database_coarsening_level2: not a level-2 database");
  if (level1_grid.level != 1) throw std::invalid_argument("database_coarsening_level2: needs the level-1 grid");
  return [&db, combos = level1_grid.combinations, fallback](const ChildIds& ids) {
    if (const CoarseMaterialFit* fit = find_level2_fit(db, combos, ids)) return coarse_quadrature_materials(*fit);
    return fallback(ids);
  };
}

}  // namespace msfab
