#include "families/families_artifact.hpp"

#include <limits>

#include "core/errors.hpp"
#include "io/artifact.hpp"

namespace msfab {

namespace {

std::string family_group(std::size_t f) { return "/families/" + std::to_string(f); }

MatX rows_of(const std::vector<VecX>& vectors, Eigen::Index cols) {
  MatX m(Eigen::Index(vectors.size()), cols);
  for (std::size_t i = 0; i < vectors.size(); ++i) m.row(Eigen::Index(i)) = vectors[i].transpose();
  return m;
}

std::vector<VecX> vectors_of(const MatX& m) {
  std::vector<VecX> v;
  for (Eigen::Index i = 0; i < m.rows(); ++i) v.push_back(m.row(i).transpose());
  return v;
}

}  // namespace

void write_families_artifact(const std::string& path, const FamiliesResult& r, const std::string& executable,
                             const std::string& config_text, const std::vector<std::string>& inputs,
                             std::uint64_t seed) {
  ArtifactWriter out(path, kFamiliesSchema, kFamiliesSchemaVersion, executable, config_text, inputs, seed);
  H5File& f = out.file();
  f.write_attribute("/", "resolution", static_cast<std::int32_t>(r.resolution));
  f.write_attribute("/", "E_stiff", r.E_stiff);
  f.write_attribute("/", "decades", r.decades);
  f.write_attribute("/", "stiff_E", r.stiff_E);
  f.write_attribute("/", "stiff_nu", r.stiff_nu);
  f.write_attribute("/", "families", static_cast<std::int32_t>(r.families.size()));
  f.write_vector("/selection", r.selection);
  f.create_group("/embedding");
  f.write_matrix("/embedding/coordinates", r.embedding);
  f.write_vector("/embedding/eigenvalues", r.eigenvalues);
  f.write_attribute("/embedding", "residual_variance", r.residual_variance);
  f.create_group("/clusters");
  f.write_vector("/clusters/label", r.labels);
  f.write_vector("/clusters/family", r.family_of);
  f.write_vector("/clusters/bic_components", r.bic_components);
  f.write_vector("/clusters/bic", r.bic);
  f.write_attribute("/clusters", "chosen", static_cast<std::int32_t>(r.clusters));
  f.create_group("/families");
  for (std::size_t k = 0; k < r.families.size(); ++k) {
    const FamilyRecord& fam = r.families[k];
    const std::string g = family_group(k);
    f.create_group(g);
    f.write_vector(g + "/members", fam.members);
    f.write_attribute(g, "representative", fam.representative);
    f.write_attribute(g, "caps", static_cast<std::int32_t>(fam.caps));
    f.write_attribute(g, "beams", static_cast<std::int32_t>(fam.representative_template.size() / 9));
    f.write_attribute(g, "representative_difference", fam.representative_difference);
    f.write_attribute(g, "E_range", std::vector<double>{fam.E_range[0], fam.E_range[1]});
    f.write_attribute(g, "nu_range", std::vector<double>{fam.nu_range[0], fam.nu_range[1]});
    f.write_attribute(g, "shear_ratio_range", std::vector<double>{fam.shear_ratio_range[0], fam.shear_ratio_range[1]});
    f.write_vector(g + "/representative_template", fam.representative_template);
    f.write_vector(g + "/member_difference", fam.member_difference);
    std::vector<std::uint8_t> kept(fam.member_kept.begin(), fam.member_kept.end());
    f.write_vector(g + "/member_kept", kept);
    f.write_matrix(g + "/member_parameters", fam.member_parameters);
    f.write_attribute(g, "has_reduced", static_cast<std::int32_t>(fam.has_reduced));
    if (fam.has_reduced) {
      const ReducedTemplate& red = fam.reduced;
      const std::string rg = g + "/reduced";
      f.create_group(rg);
      f.write_vector(rg + "/base", red.base);
      f.write_matrix(rg + "/plus", rows_of(red.plus, red.base.size()));
      f.write_matrix(rg + "/minus", rows_of(red.minus, red.base.size()));
      f.write_matrix(rg + "/property_slope", red.property_slope);
      f.write_attribute(rg, "components", static_cast<std::int32_t>(red.components));
      f.write_attribute(rg, "explained_variance", red.explained_variance);
      f.write_attribute(rg, "regression_r2", std::vector<double>{red.regression_r2[0], red.regression_r2[1]});
    }
  }
  out.commit();
}

FamiliesResult read_families_artifact(const std::string& path) {
  ArtifactReader in(path, kFamiliesSchema, kFamiliesSchemaVersion);
  const H5File& f = in.file();
  FamiliesResult r;
  r.resolution = f.read_attribute<std::int32_t>("/", "resolution");
  r.E_stiff = f.read_attribute<double>("/", "E_stiff");
  r.decades = f.read_attribute<double>("/", "decades");
  r.stiff_E = f.read_attribute<double>("/", "stiff_E");
  r.stiff_nu = f.read_attribute<double>("/", "stiff_nu");
  const int families = f.read_attribute<std::int32_t>("/", "families");
  r.selection = f.read_vector<std::int64_t>("/selection");
  r.embedding = f.read_matrix<double>("/embedding/coordinates", -1, Finite::nan_means_missing);
  const std::vector<double> eigenvalues = f.read_vector<double>("/embedding/eigenvalues");
  r.eigenvalues = Eigen::Map<const VecX>(eigenvalues.data(), Eigen::Index(eigenvalues.size()));
  r.residual_variance = f.read_attribute<double>("/embedding", "residual_variance");
  r.labels = f.read_vector<int>("/clusters/label");
  r.family_of = f.read_vector<int>("/clusters/family");
  r.bic_components = f.read_vector<int>("/clusters/bic_components");
  r.bic = f.read_vector<double>("/clusters/bic");
  r.clusters = f.read_attribute<std::int32_t>("/clusters", "chosen");
  if (r.labels.size() != r.selection.size() || r.family_of.size() != r.selection.size())
    throw InputError(path + ": /clusters/label and /clusters/family must have one entry per selected structure");
  for (int k = 0; k < families; ++k) {
    const std::string g = family_group(std::size_t(k));
    if (!f.is_group(g))
      throw InputError(path + ": attribute 'families' is " + std::to_string(families) + " but group " + g +
                       " is missing");
    FamilyRecord fam;
    fam.members = f.read_vector<std::int64_t>(g + "/members");
    fam.representative = f.read_attribute<std::int64_t>(g, "representative");
    fam.caps = f.read_attribute<std::int32_t>(g, "caps") != 0;
    const std::vector<double> tpl = f.read_vector<double>(g + "/representative_template");
    if (tpl.size() % 9 != 0)
      throw InputError(path + ": " + g + "/representative_template has " + std::to_string(tpl.size()) +
                       " values, not 9 per beam");
    fam.representative_template = Eigen::Map<const VecX>(tpl.data(), Eigen::Index(tpl.size()));
    fam.representative_difference = f.read_attribute<double>(g, "representative_difference");
    const auto range = [&](const char* name, double* out) {
      const std::vector<double> v = f.read_attribute_vector<double>(g, name);
      if (v.size() != 2) throw InputError(path + ": " + g + " attribute '" + name + "' must hold 2 values");
      out[0] = v[0], out[1] = v[1];
    };
    range("E_range", fam.E_range);
    range("nu_range", fam.nu_range);
    range("shear_ratio_range", fam.shear_ratio_range);
    fam.member_difference = f.read_vector<double>(g + "/member_difference", Finite::nan_means_missing);
    const std::vector<std::uint8_t> kept = f.read_vector<std::uint8_t>(g + "/member_kept");
    fam.member_kept.assign(kept.begin(), kept.end());
    fam.member_parameters = f.read_matrix<double>(g + "/member_parameters", -1, Finite::nan_means_missing);
    if (fam.member_difference.size() != fam.members.size() || fam.member_kept.size() != fam.members.size())
      throw InputError(path + ": " + g + ": member datasets disagree in length with " + g + "/members");
    fam.has_reduced = f.read_attribute<std::int32_t>(g, "has_reduced") != 0;
    if (fam.has_reduced) {
      const std::string rg = g + "/reduced";
      ReducedTemplate& red = fam.reduced;
      const std::vector<double> base = f.read_vector<double>(rg + "/base");
      red.base = Eigen::Map<const VecX>(base.data(), Eigen::Index(base.size()));
      red.plus = vectors_of(f.read_matrix<double>(rg + "/plus", Eigen::Index(base.size())));
      red.minus = vectors_of(f.read_matrix<double>(rg + "/minus", Eigen::Index(base.size())));
      red.property_slope = f.read_matrix<double>(rg + "/property_slope");
      red.components = f.read_attribute<std::int32_t>(rg, "components");
      red.explained_variance = f.read_attribute<double>(rg, "explained_variance");
      const std::vector<double> r2 = f.read_attribute_vector<double>(rg, "regression_r2");
      if (r2.size() == 2) red.regression_r2[0] = r2[0], red.regression_r2[1] = r2[1];
      if (red.plus.size() != red.minus.size() || base.size() % 9 != 0)
        throw InputError(path + ": " + rg + ": plus and minus templates disagree, or the base is not 9 per beam");
    }
    r.families.push_back(std::move(fam));
  }
  return r;
}

}  // namespace msfab
