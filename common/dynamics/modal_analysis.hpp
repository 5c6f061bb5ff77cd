#pragma once
// Natural vibration modes of a hex mesh about its rest state: the lowest
// eigenpairs of K x = lambda M x (thesis Eq. 4.15), with K the elastic
// tangent stiffness at rest and M the consistent mass of App. B.4. These are
// the deformation modes and numerical eigenvalues lambda_i^0 that
// dynamics-aware coarsening compares and rescales (§4.3.1-4.3.2).
//
// Method: shift-invert block Krylov iteration in the M inner product with
// Rayleigh-Ritz on the original pencil, restarted from the best Ritz
// vectors. Each cycle M-orthonormalizes span{X, O X, ..., O^(d-1) X} with
// O = (K - sigma M)^{-1} M (one CHOLMOD factorization for the whole run) and
// solves the small dense pencil (V^T K V, V^T M V). Start vectors are a fixed
// pseudo-random sequence, so results are reproducible for a given thread
// count (the CHOLMOD factorization's round-off depends on it).
#include <limits>
#include <vector>

#include "core/types.hpp"
#include "fem/hex_mesh.hpp"

namespace msfab {

struct ModalOptions {
  int num_modes = 4;  // k: modes reported (after skipping rigid ones)
  // Skip modes whose eigenvalue is below rigid_threshold * stiffness_scale
  // (stiffness_scale = tr(K_free) / tr(M_free), the order of the largest
  // eigenvalues): a body with no or too few fixed DOFs has up to 6 rigid
  // modes at lambda = 0 whose computed values are of round-off size.
  bool skip_rigid = false;
  double rigid_threshold = 1e-10;
  // sigma of the shift-invert operator; NaN picks -shift_fraction *
  // stiffness_scale, negative so that K - sigma M is positive definite also
  // for a singular (free) K. If that factorization is still not positive
  // definite the automatic shift is moved down tenfold (up to 6 times); a
  // user-given shift is used as is.
  double shift = std::numeric_limits<double>::quiet_NaN();
  double shift_fraction = 1e-6;
  // Converged when every reported mode has ||K x - lambda M x|| / ||K x||
  // (over the free DOFs) below this; see ModalResult::residuals for
  // reported rigid modes. A residual that stalls within 100x of it for 20
  // cycles is accepted as the round-off floor (ModalResult::residuals
  // reports what was reached).
  double tolerance = 1e-8;
  int max_cycles = 200;
  // Block width p (0: max(2 m, m + 6) with m the modes wanted, rigid ones
  // included) and Krylov depth d in blocks per restart cycle.
  int block_size = 0;
  int krylov_blocks = 3;
  // Eigenvalues whose relative gap is below this are one repeated
  // eigenvalue (all rigid modes form one group too). A repeated eigenspace
  // has no preferred basis and the solver would return whatever round-off
  // picks, so it is rotated into a basis fixed by geometry: the eigenvectors
  // of Q_ab = x_a^T W M x_b with W = diag(3, 2, 1) weighting the x, y, z
  // displacement of every node, largest Q first. For a square beam along x
  // this gives y bending, then z bending (each with its own Poisson
  // contraction), on any mesh, so mode
  // shapes can be compared across resolutions. The rotation is orthogonal
  // within the group (M-orthonormality is kept); eigenvalues become the
  // Rayleigh quotients of the rotated vectors. When node positions are
  // known, modes that W leaves tied (identical disconnected bodies) are
  // separated by a second weighting that also grows along a fixed oblique
  // direction in space. 0 disables it.
  double repeated_tolerance = 1e-8;
  int threads = 0;  // OpenMP threads for the solver's BLAS; 0 = default
};

struct ModalResult {
  VecX eigenvalues;  // lambda_i ascending (rad^2/s^2)
  VecX frequencies;  // f_i = sqrt(max(lambda_i, 0)) / (2 pi), Hz
  // One column per mode, full DOF length (node-major 3 n + a), zero at fixed
  // DOFs, M-orthonormal: modes^T M modes = I. Sign: the entry of largest
  // magnitude (first such) is positive.
  MatX modes;
  // ||K x - lambda M x|| / ||K x|| per mode over the free DOFs (the rows of
  // clamped DOFs hold reaction forces); for a reported rigid mode
  // (lambda below the rigid threshold) the denominator is
  // stiffness_scale * ||M x|| because K x vanishes.
  VecX residuals;
  int cycles = 0;                 // restart cycles of the block Krylov iteration
  int operator_applications = 0;  // solves with K - sigma M
  int rigid_modes_skipped = 0;
  double shift = 0.0;            // sigma actually used
  double stiffness_scale = 0.0;  // tr(K_free) / tr(M_free)
};

// K and M are symmetric with both triangles stored (as ElasticAssembler and
// expand_to_dofs give them). fixed: one flag per DOF (1 = clamped), or empty
// for a free body; clamped DOFs are eliminated. InputError for inconsistent
// sizes or options; NumericalError if K - sigma M cannot be factorized or the
// iteration does not reach the tolerance within max_cycles. rest_positions
// (one row per node, optional) only serve the canonical basis of repeated
// eigenvalues.
ModalResult modal_analysis(const SpMat& K, const SpMat& M, const std::vector<char>& fixed,
                           const ModalOptions& options = {}, const NodeArray* rest_positions = nullptr);

// Peak memory of modal_analysis on a mesh of `elements` hexahedra with
// `dofs` DOFs, in bytes: assembly and the CHOLMOD factor of K - sigma M
// (12 kB per element + 0.7 kB x elements^(4/3)) plus the Krylov basis and
// its products (8 B x dofs x (3 krylov_blocks + 6) x block width). Measured
// with /usr/bin/time on the plucked cantilever at 2 160 / 10 000 / 33 750
// elements (docs/cli.md, "Memory").
double modal_analysis_peak_bytes(double elements, double dofs, const ModalOptions& options);

// Assembles K at the rest positions and the consistent mass from per-element
// densities, then calls the function above.
ModalResult modal_analysis(const HexMesh& mesh, const std::vector<double>& density, const std::vector<char>& fixed,
                           const ModalOptions& options = {});

}  // namespace msfab
