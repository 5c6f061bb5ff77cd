#include "material/material_sum.hpp"

#include <algorithm>

#include "core/errors.hpp"

namespace msfab {

MaterialSum::MaterialSum(std::vector<MaterialPtr> terms) : terms_(std::move(terms)) {
  if (terms_.empty()) throw InputError("material sum needs at least one term, got none");
  for (size_t i = 0; i < terms_.size(); ++i)
    if (!terms_[i]) throw InputError("material sum term " + std::to_string(i) + " is null");
}

void MaterialSum::evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const {
  double psi_term = 0.0;
  Mat3 P_term;
  Mat9 H_term;
  if (psi) *psi = 0.0;
  if (P) P->setZero();
  if (dPdF) dPdF->setZero();
  for (const MaterialPtr& m : terms_) {
    m->evaluate(F, psi ? &psi_term : nullptr, P ? &P_term : nullptr, dPdF ? &H_term : nullptr);
    if (psi) *psi += psi_term;
    if (P) *P += P_term;
    if (dPdF) *dPdF += H_term;
  }
}

double MaterialSum::shear_modulus() const {
  double s = 0.0;
  for (const MaterialPtr& m : terms_) s += m->shear_modulus();
  return s;
}

double MaterialSum::lame_lambda() const {
  double s = 0.0;
  for (const MaterialPtr& m : terms_) s += m->lame_lambda();
  return s;
}

std::string MaterialSum::name() const {
  std::string s = "sum(";
  for (size_t i = 0; i < terms_.size(); ++i) s += (i ? "+" : "") + terms_[i]->name();
  return s + ")";
}

bool MaterialSum::frame_indifferent() const {
  return std::all_of(terms_.begin(), terms_.end(), [](const MaterialPtr& t) { return t->frame_indifferent(); });
}

}  // namespace msfab
