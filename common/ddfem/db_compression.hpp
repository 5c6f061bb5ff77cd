#pragma once
// Compression of a coarse-material database (thesis §2.3.4): every coarse
// material gets a feature vector of log-energies on a common set of
// deformations of the coarse element; k representatives are chosen by
// farthest-point sampling in the distance of Eq. 2.10, and every
// combination is looked up to its nearest representative.
#include <cstdint>
#include <random>
#include <vector>

#include "ddfem/coarse_db.hpp"
#include "ddfem/fine_block.hpp"

namespace msfab {

// A uniform draw in [-1, 1) from the standardized mt19937_64 sequence (the
// same on every platform, unlike std::uniform_real_distribution).
double uniform_pm1(std::mt19937_64& rng);

// Common deformations: corner displacements (24) of the coarse element of
// `coarse_rest` (edge 2h), each a random small strain (Frobenius norm
// `strain`) plus a non-affine corner perturbation of a third of it, drawn
// from the standardized mt19937_64 sequence of `seed`.
std::vector<Vec24> common_deformations(const hex8::NodeMatrix& coarse_rest, int count, double strain,
                                       std::uint64_t seed);
// The 24 single-corner moves: corner c displaced by `strain` times the edge
// along one axis, every other corner at rest. Smooth deformations see a
// block's stiffness as a whole; these see where in the block it sits (the
// energy of a corner's move comes mostly from the points next to it), so a
// checkerboard block is not taken for another block with as much stiff
// material elsewhere (docs/ddfem.md, "Compression").
std::vector<Vec24> corner_deformations(const hex8::NodeMatrix& coarse_rest, double strain);

// Row e: log V_s of entry e at deformation s (Eq. 2.10's feature vector).
// InputError if an entry's energy is not positive and finite at a deformation.
MatX energy_features(const std::vector<CoarseMaterialFit>& entries, const std::vector<Vec24>& deformations,
                     double voxel_size);

struct FarthestPointSet {
  std::vector<int> representatives;  // rows, in the order chosen
  std::vector<int> nearest;          // per row: position in `representatives` of the closest one
  std::vector<double> distance;      // per row: Eq. 2.10 distance to it
};
// Starts with the rows `seeds` (in order, repeats skipped), then repeatedly
// adds the row farthest from all chosen ones (ties: lowest row) until k are
// chosen. Nearest ties: the earlier representative. A representative's
// nearest is itself.
FarthestPointSet farthest_point_sampling(const MatX& features, int k, const std::vector<int>& seeds);
inline FarthestPointSet farthest_point_sampling(const MatX& features, int k, int first) {
  return farthest_point_sampling(features, k, std::vector<int>{first});
}

// Blocks of one material are kept exactly: they are the common case in a
// design (every uniform region), so compression seeds farthest-point
// sampling with them instead of a random start (docs/ddfem.md).
bool is_homogeneous(const BlockMaterials& ids);

struct CompressionReport {
  double mean_distance = 0, max_distance = 0;  // combinations to their representative (Eq. 2.10)
  double mean_energy_error = 0;                // mean |V_rep / V_own - 1| over combinations and deformations
};

// A database whose entries are k representatives of `full` (which must be
// uncompressed), with entry_of mapping every combination to its
// representative. The homogeneous combinations come first (if k allows),
// then farthest-point sampling; `seed` draws the common deformations.
// `corner_moves` appends corner_deformations to the common ones.
CoarseDatabase compress_database(const CoarseDatabase& full, int k, int deformations, double strain, std::uint64_t seed,
                                 CompressionReport* report = nullptr, bool corner_moves = false);

}  // namespace msfab
