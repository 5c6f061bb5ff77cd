#pragma once
// One design cell's share of the MMA subproblem (Svanberg 1987, 2002) when
// every constraint but one belongs to a single cell.
//
// The two-scale problem 3.5 has a handful of constraints per cell (the
// gamut's Phi and the Voigt bound's conditions) and at most one that spans
// the design (the mass budget). In MMA every function is replaced by a
// convex separable approximation around the iterate x^k,
//
//   f~(x) = sum_j p_j / (U_j - x_j) + q_j / (x_j - L_j) - b,
//
// so the subproblem's Lagrangian separates over cells once the budget's
// multiplier mu is fixed: each cell maximizes its own small concave dual
// over the multipliers lambda >= 0 of its constraints (here by projected
// Newton), and one scalar search over mu meets the budget. As in
// Svanberg's method, each cell constraint c gets an artificial slack
// y_c >= 0 priced c_pen y_c + y_c^2 / 2, so the subproblem always has a
// solution (a start outside the gamut, or a cell the move limits keep
// outside) and the slack is zero wherever the cell can meet the constraint
// with a multiplier below c_pen.
//
// For the budget search each cell also returns the derivative of its
// approximate mass along the solution path, d m~ / d mu (implicit
// differentiation of its dual optimality conditions): a Newton step on mu.
#include <Eigen/Dense>

namespace msfab {

// Sizes: the gamut spaces have at most 5 parameters (orthotropic2d) and
// 1 + 9 conditions per cell (Phi and the orthotropic Voigt bound).
constexpr int kCellMmaMaxVariables = 6;
constexpr int kCellMmaMaxConstraints = 10;

using CellMmaVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kCellMmaMaxVariables, 1>;
using CellMmaConstraintVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kCellMmaMaxConstraints, 1>;
using CellMmaMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kCellMmaMaxConstraints, kCellMmaMaxVariables>;
using CellMmaSquare =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kCellMmaMaxConstraints, kCellMmaMaxConstraints>;

// The approximations of one cell around its iterate x^k.
struct CellMmaApproximation {
  CellMmaVec lower, upper;  // asymptotes L, U
  CellMmaVec alpha, beta;   // move limits: alpha <= x <= beta, L < alpha, beta < U
  CellMmaVec p0, q0;        // the objective
  CellMmaMatrix p, q;       // the cell's constraints (rows), each  <= b
  CellMmaConstraintVec b;
  CellMmaVec pm, qm;  // the cell's share of the budget (its approximate mass is sum pm/(U-x) + qm/(x-L) - bm)
  double bm = 0;
  int variables() const { return int(lower.size()); }
  int constraints() const { return int(b.size()); }
};

// The standard MMA coefficients of a function with value `value` and
// gradient `gradient` at x (Svanberg 2007: 1.001 / 0.001 split of the
// gradient's sign, plus `raa0` / (x_max - x_min) for strict convexity);
// returns b such that p / (U - x) + q / (x - L) - b equals value at x.
double mma_coefficients(const CellMmaVec& x, const CellMmaVec& lower, const CellMmaVec& upper,
                        const CellMmaVec& gradient, double value, const CellMmaVec& range, double raa0, CellMmaVec& p,
                        CellMmaVec& q);

struct CellMmaSolution {
  CellMmaVec x;                 // the subproblem's minimizer
  CellMmaConstraintVec lambda;  // the cell constraints' multipliers
  double mass = 0;              // the approximate mass at x
  double mass_derivative = 0;   // d mass / d mu (<= 0)
  double slack = 0;             // largest artificial slack y_c (0: every approximate constraint met)
  int newton_iterations = 0;
  bool converged = false;
};

// Maximizes the cell's dual at budget multiplier mu >= 0, starting from
// `lambda_start` (a previous solution's multipliers, or empty for zeros).
// `penalty` is c_pen; the dual's projected gradient is driven below
// `tolerance` (in the constraints' units).
CellMmaSolution solve_cell_mma(const CellMmaApproximation& a, double mu, const CellMmaConstraintVec& lambda_start,
                               double penalty, double tolerance);

}  // namespace msfab
