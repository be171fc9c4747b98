// The world's constraint solver (see constraint_solver.hpp). In Bullet's terms a
// row i of a group has a Jacobian J_i (m_contactNormal1/2 and m_relpos1/2CrossNormal
// on its two solver bodies), a target velocity m_rhs / m_jacDiagABInv, a
// constraint-force mixing, and bounds on its total impulse. Sequential impulses
// drive each row's residual to zero one row at a time; here the residuals of all
// rows are zeroed at once: A dl = r with A = J M^-1 J^T + cfm, within the bounds.
#include "constraint_solver.hpp"

#include <algorithm>
#include <cmath>

namespace afhub::physics {
namespace {

constexpr int K = ConstraintSolver::kMaxDirectRows;  // the matrices' row stride
// A row whose pivot keeps less than this share of its own diagonal in the shape
// metric (factor(): a Jacobian within about 2 degrees of a combination of the rows
// before it) is taken as implied by them. A planar loop of 3D joints repeats rows
// exactly; a loop drawn in CAD repeats them to within its drawing's error (the ECM's
// axes disagree by about 0.3 degrees: held exactly, its yaw locked; it needs more
// than 1e-5 here, and the stress loops of closed_loop_test hold up to 3e-2).
constexpr double kDependent = 1e-3;
constexpr double kUnbounded = 1e30;
constexpr int kSchurSweeps = 100;

double dot(const btVector3& a, const btVector3& b) {
  return a.dot(b);
}

bool bounded(const btSolverConstraint& row) {
  return row.m_lowerLimit > -kUnbounded || row.m_upperLimit < kUnbounded;
}

double target(const btSolverConstraint& row) {
  return row.m_rhs / row.m_jacDiagABInv;
}

double cfm(const btSolverConstraint& row) {
  return row.m_cfm / row.m_jacDiagABInv;
}

}  // namespace

ConstraintSolver::ConstraintSolver(int bodies, int joints) : body_capacity_(bodies + 64) {
  constexpr int kContacts = 4096;  // contact points, each with two friction rows
  const int joint_rows = 6 * joints + 64;
  m_tmpSolverBodyPool.reserve(body_capacity_);
  m_tmpSolverContactConstraintPool.reserve(kContacts);
  m_tmpSolverContactFrictionConstraintPool.reserve(2 * kContacts);
  m_tmpSolverContactRollingFrictionConstraintPool.reserve(3 * kContacts);
  m_tmpSolverNonContactConstraintPool.reserve(joint_rows);
  m_orderTmpConstraintPool.reserve(kContacts);
  m_orderFrictionConstraintPool.reserve(2 * kContacts);
  m_orderNonContactConstraintPool.reserve(joint_rows);
  m_tmpConstraintSizesPool.reserve(joints + 64);
}

void ConstraintSolver::enable_direct_solve() {
  sides_.resize(2 * K);
  next_side_.resize(2 * K);
  body_rows_.reserve(body_capacity_);
  body_first_row_.reserve(body_capacity_);
  equality_.reserve(K);
  bounded_.reserve(K);
  row_.resize(K);
  bounded_slot_.resize(K);
  dependent_.resize(K);
  row_first_.resize(K);
  at_or_after_.resize(K);
  first_.resize(K);
  last_.resize(K);
  for (auto* matrix : {&a_, &shape_, &factor_, &null_, &gram_, &w_, &schur_}) matrix->resize(K * K);
  for (auto* vector :
       {&residual_, &equality_solution_, &bounded_solution_, &reduced_rhs_, &gram_rhs_})
    vector->resize(K);
}

btScalar ConstraintSolver::solveGroupCacheFriendlyIterations(
    btCollisionObject** bodies, int numBodies, btPersistentManifold** manifolds, int numManifolds,
    btTypedConstraint** constraints, int numConstraints, const btContactSolverInfo& info,
    btIDebugDraw* debug_drawer) {
  const auto iterate = [&] {
    return btMultiBodyConstraintSolver::solveGroupCacheFriendlyIterations(
        bodies, numBodies, manifolds, numManifolds, constraints, numConstraints, info,
        debug_drawer);
  };
  // Any marked joint makes the island direct. Rows a loop repeats are looked for
  // when a joint in it is marked so, or a constraint is not marked at all (an
  // actuator's hold, which may close a loop while running).
  bool direct = false, find_dependent = false;
  for (int c = 0; c < numConstraints; ++c) {
    const int type = constraints[c]->getUserConstraintType();
    direct |= type == kInLoopIsland || type == kInTreeIsland;
    find_dependent |= type != kInTreeIsland;
  }
  // A multibody's rows (a chain in reduced coordinates touching the island) are not
  // in the pools below: such an island is iterated.
  const bool multibody_rows = m_multiBodyNonContactConstraints.size() > 0 ||
                              m_multiBodyNormalContactConstraints.size() > 0 ||
                              m_multiBodyFrictionContactConstraints.size() > 0 ||
                              m_multiBodyTorsionalFrictionContactConstraints.size() > 0;
  if (!direct || a_.empty() || multibody_rows) return iterate();
  // Every row of the island: joints, then contacts, then their friction and rolling
  // friction (bounded by the contact's own impulse).
  btConstraintArray& joints = m_tmpSolverNonContactConstraintPool;
  btConstraintArray& contacts = m_tmpSolverContactConstraintPool;
  btConstraintArray& frictions = m_tmpSolverContactFrictionConstraintPool;
  btConstraintArray& rollings = m_tmpSolverContactRollingFrictionConstraintPool;
  rows_ = joints.size() + contacts.size() + frictions.size() + rollings.size();
  if (rows_ > K) return iterate();
  int r = 0;
  for (int i = 0; i < joints.size(); ++i, ++r) row_[r] = {&joints[i], -1, false};
  const int first_contact = r;
  for (int i = 0; i < contacts.size(); ++i, ++r) row_[r] = {&contacts[i], -1, false};
  for (int i = 0; i < frictions.size(); ++i, ++r)
    row_[r] = {&frictions[i], first_contact + frictions[i].m_frictionIndex, false};
  for (int i = 0; i < rollings.size(); ++i, ++r)
    row_[r] = {&rollings[i], first_contact + rollings[i].m_frictionIndex, true};
  // Penetration is pushed out apart from the velocities (Bullet's split impulse).
  solveGroupCacheFriendlySplitImpulseIterations(bodies, numBodies, manifolds, numManifolds,
                                                constraints, numConstraints, info, debug_drawer);
  factor(find_dependent);
  if (!solve_rows())  // then as Bullet would have (the split impulse is done)
    for (int iteration = 0; iteration < info.m_numIterations; ++iteration)
      solveSingleIteration(iteration, bodies, numBodies, manifolds, numManifolds, constraints,
                           numConstraints, info, debug_drawer);
  return 0;
}

// A, its equality rows' Cholesky factor (dependent rows left out, when looked for)
// with the null vectors the dependent rows make, W and S.
void ConstraintSolver::factor(bool find_dependent) noexcept {
  for (int i = 0; i < rows_; ++i) {
    const btSolverConstraint& row = *row_[i].row;
    auto side = [&](int body, const btVector3& normal, const btVector3& turn,
                    const btVector3& angular_component) {
      const btSolverBody& solver_body = m_tmpSolverBodyPool[body];
      Side out{body, solver_body.m_originalBody != nullptr, normal, turn};
      if (out.moves) {
        out.linear = normal * solver_body.m_invMass * solver_body.m_linearFactor;
        out.angular = angular_component * solver_body.m_angularFactor;
      }
      return out;
    };
    sides_[2 * i] = side(row.m_solverBodyIdA, row.m_contactNormal1, row.m_relpos1CrossNormal,
                         row.m_angularComponentA);
    sides_[2 * i + 1] = side(row.m_solverBodyIdB, row.m_contactNormal2, row.m_relpos2CrossNormal,
                             row.m_angularComponentB);
  }
  equality_.clear();
  bounded_.clear();
  // The island's length L: the root mean square of its rows' lever arms. Rows
  // compared by shape weigh a turn by L, as a point L away sees it (shape_ below).
  double levers2 = 0.0;
  int levers = 0;
  for (int i = 0; i < rows_ && find_dependent; ++i) {
    const btSolverConstraint& row = *row_[i].row;
    if (row.m_contactNormal1.length2() > 0) {
      levers2 += row.m_relpos1CrossNormal.length2() + row.m_relpos2CrossNormal.length2();
      levers += 2;
    }
  }
  const double turn_weight = levers2 > 0 ? levers / levers2 : 1.0;  // 1 / L^2
  // Row i's velocity change per unit impulse of row j (mass), and the two rows'
  // Jacobians' product (shape), through each moving body they share: summed over
  // the rows meeting at each body (a list per body), so that an open chain's rows
  // cost their neighbours, not the whole island.
  body_rows_.assign(m_tmpSolverBodyPool.size(), -1);
  body_first_row_.assign(m_tmpSolverBodyPool.size(), -1);
  for (int i = 0; i < rows_; ++i) {
    std::fill_n(&a_[i * K], i + 1, 0.0);
    if (find_dependent) std::fill_n(&shape_[i * K], i + 1, 0.0);
    row_first_[i] = i;
    for (int s = 0; s < 2; ++s) {
      const Side& side = sides_[2 * i + s];
      if (!side.moves) continue;
      next_side_[2 * i + s] = body_rows_[side.body];
      body_rows_[side.body] = 2 * i + s;
      if (body_first_row_[side.body] < 0) body_first_row_[side.body] = i;
      row_first_[i] = std::min(row_first_[i], body_first_row_[side.body]);
    }
  }
  for (const int first : body_rows_)
    for (int e = first; e >= 0; e = next_side_[e])
      for (int f = e; f >= 0; f = next_side_[f]) {
        const Side& se = sides_[e];
        const Side& sf = sides_[f];
        const int i = e / 2, j = f / 2;
        const double mass = dot(se.normal, sf.linear) + dot(se.turn, sf.angular);
        a_[i * K + j] += mass;
        if (!find_dependent) continue;
        const double shape = dot(se.normal, sf.normal) + dot(se.turn, sf.turn) * turn_weight;
        shape_[i * K + j] += shape;
      }
  for (int i = 0; i < rows_; ++i) {
    const btSolverConstraint& ri = *row_[i].row;
    // A row with no effective mass (its bodies cannot move along it) takes no part.
    bounded_slot_[i] = -1;
    if (ri.m_jacDiagABInv == 0 || !(a_[i * K + i] > 0)) continue;
    a_[i * K + i] += cfm(ri);
    if (bounded(ri)) {
      bounded_slot_[i] = static_cast<int>(bounded_.size());
      bounded_.push_back(i);
    } else {
      equality_.push_back(i);
    }
  }

  // Which rows a loop repeats is a matter of shape, not of mass: it is judged on the
  // Jacobians' products (a turn weighed by the island's length, so that a robot drawn
  // ten times smaller is judged alike), where a mass ratio of a thousand cannot make
  // a row look implied. Then A itself is factored over the rows kept.
  const int ne = static_cast<int>(equality_.size());
  std::fill(dependent_.begin(), dependent_.begin() + ne, false);
  if (find_dependent) cholesky(shape_.data(), true);
  cholesky(a_.data(), false);

  // A dependent row d repeats a combination c of the rows kept: A's null space
  // holds n = e_d - c, and A reaches only right-hand sides orthogonal to every n.
  nulls_ = 0;
  for (int k = 0; k < ne; ++k) {
    if (!dependent_[k]) continue;
    double* n = &null_[nulls_ * K];
    for (int j = 0; j < ne; ++j) n[j] = a(equality_[j], equality_[k]);
    solve_kept(n);
    for (int j = 0; j < ne; ++j) n[j] = -n[j];
    n[k] = 1.0;
    ++nulls_;
  }
  // The null vectors' Gram matrix, Cholesky-factored in place (its lower half).
  for (int p = 0; p < nulls_; ++p)
    for (int q = 0; q <= p; ++q) {
      double sum = 0.0;
      for (int j = 0; j < ne; ++j) sum += null_[p * K + j] * null_[q * K + j];
      for (int m = 0; m < q; ++m) sum -= gram_[p * K + m] * gram_[q * K + m];
      gram_[p * K + q] = p == q ? std::sqrt(sum) : sum / gram_[q * K + q];
    }

  // W's row b is A_ee^+ times A's equality entries of bounded row b.
  const int nb = static_cast<int>(bounded_.size());
  for (int b = 0; b < nb; ++b) {
    double* w = &w_[b * K];
    for (int k = 0; k < ne; ++k) w[k] = a(bounded_[b], equality_[k]);
    solve_equality(w);
  }
  for (int b1 = 0; b1 < nb; ++b1)
    for (int b2 = 0; b2 < nb; ++b2) {
      double sum = a(bounded_[b1], bounded_[b2]);
      for (int k = 0; k < ne; ++k) sum -= a(bounded_[b1], equality_[k]) * w_[b2 * K + k];
      schur_[b1 * K + b2] = sum;
    }
}

// The Cholesky factor of m's equality block into factor_, leaving out the rows
// marked dependent and, when `judge`, marking those whose pivot keeps less than
// kDependent of their own diagonal. A row meets only the rows sharing one of its
// two bodies, so it starts late: its factor row starts where it does (fill-in stays
// within that envelope), and the products skip the zeros before it. A column ends
// at the last row whose envelope reaches it: an open chain's factor is a band.
void ConstraintSolver::cholesky(const double* m, bool judge) noexcept {
  const int ne = static_cast<int>(equality_.size());
  double* l = factor_.data();
  // Row k's first nonzero is looked for from the first equality row at or after its
  // row_first_: a chain's rows skip the whole island before them.
  for (int r = rows_ - 1, position = ne; r >= 0; --r) {
    if (position > 0 && equality_[position - 1] == r) --position;
    at_or_after_[r] = position;
  }
  for (int k = 0; k < ne; ++k) {
    int first = at_or_after_[row_first_[equality_[k]]];
    while (first < k && m[equality_[k] * K + equality_[first]] == 0.0) ++first;
    first_[k] = first;
    last_[k] = k;
    for (int j = first; j < k; ++j) last_[j] = k;
  }
  for (int k = 0; k < ne; ++k) {
    const double* lk = &l[k * K];
    const double own = m[equality_[k] * K + equality_[k]];
    double d = own;
    for (int j = first_[k]; j < k; ++j) d -= lk[j] * lk[j];
    if (judge && d <= kDependent * own) dependent_[k] = true;
    if (!dependent_[k] && !(d > 0)) dependent_[k] = true;  // round-off on a kept row
    const double pivot = dependent_[k] ? 0.0 : std::sqrt(d);
    l[k * K + k] = pivot;
    for (int i = k + 1; i <= last_[k]; ++i) {
      if (first_[i] > k) continue;  // outside row i's envelope: zero, never read
      double sum = 0.0;
      if (!dependent_[k]) {
        const double* li = &l[i * K];
        sum = m[equality_[i] * K + equality_[k]];
        for (int j = std::max(first_[i], first_[k]); j < k; ++j) sum -= li[j] * lk[j];
        sum /= pivot;
      }
      l[i * K + k] = sum;
    }
  }
}

// v <- A_kk^-1 v over the kept equality rows (the dependent ones get 0).
void ConstraintSolver::solve_kept(double* v) const noexcept {
  const int ne = static_cast<int>(equality_.size());
  const double* l = factor_.data();
  for (int k = 0; k < ne; ++k) {
    if (dependent_[k]) {
      v[k] = 0.0;
      continue;
    }
    double sum = v[k];
    for (int j = first_[k]; j < k; ++j) sum -= l[k * K + j] * v[j];
    v[k] = sum / l[k * K + k];
  }
  for (int k = ne - 1; k >= 0; --k) {
    if (dependent_[k]) continue;
    double sum = v[k];
    for (int i = k + 1; i <= last_[k]; ++i)
      if (first_[i] <= k) sum -= l[i * K + k] * v[i];
    v[k] = sum / l[k * K + k];
  }
}

// v <- A_ee^+ v: v's part that no impulse can reach (along the null vectors) is
// dropped first, so that the rows share a loop's inconsistency in least squares
// instead of the dependent rows taking all of it.
void ConstraintSolver::solve_equality(double* v) noexcept {
  const int ne = static_cast<int>(equality_.size());
  double* g = gram_rhs_.data();
  for (int p = 0; p < nulls_; ++p) {
    double sum = 0.0;
    for (int j = 0; j < ne; ++j) sum += null_[p * K + j] * v[j];
    for (int m = 0; m < p; ++m) sum -= gram_[p * K + m] * g[m];
    g[p] = sum / gram_[p * K + p];
  }
  for (int p = nulls_ - 1; p >= 0; --p) {
    double sum = g[p];
    for (int m = p + 1; m < nulls_; ++m) sum -= gram_[m * K + p] * g[m];
    g[p] = sum / gram_[p * K + p];
  }
  for (int p = 0; p < nulls_; ++p)
    for (int j = 0; j < ne; ++j) v[j] -= null_[p * K + j] * g[p];
  solve_kept(v);
}

// Zeroes every row's residual at once, from the bodies' velocities so far: the
// equality rows exactly (in least squares where a loop repeats rows), the bounded
// rows (limits, motors, contacts, friction) within their bounds. False, with nothing
// applied, when the solution is not finite (a factorisation gone wrong).
bool ConstraintSolver::solve_rows() noexcept {
  for (int i = 0; i < rows_; ++i) {
    const btSolverConstraint& row = *row_[i].row;
    if (row.m_jacDiagABInv == 0) continue;
    const btSolverBody& a = m_tmpSolverBodyPool[row.m_solverBodyIdA];
    const btSolverBody& b = m_tmpSolverBodyPool[row.m_solverBodyIdB];
    residual_[i] = target(row) - cfm(row) * row.m_appliedImpulse -
                   dot(row.m_contactNormal1, a.m_deltaLinearVelocity) -
                   dot(row.m_relpos1CrossNormal, a.m_deltaAngularVelocity) -
                   dot(row.m_contactNormal2, b.m_deltaLinearVelocity) -
                   dot(row.m_relpos2CrossNormal, b.m_deltaAngularVelocity);
  }
  const int ne = static_cast<int>(equality_.size());
  const int nb = static_cast<int>(bounded_.size());
  double* y = equality_solution_.data();
  for (int k = 0; k < ne; ++k) y[k] = residual_[equality_[k]];
  solve_equality(y);
  // The bounded rows: projected Gauss-Seidel on S x = r_b - A_be y, which is small.
  double* x = bounded_solution_.data();
  for (int b = 0; b < nb; ++b) {
    double sum = residual_[bounded_[b]];
    for (int k = 0; k < ne; ++k) sum -= a(bounded_[b], equality_[k]) * y[k];
    reduced_rhs_[b] = sum;
    x[b] = 0.0;
  }
  for (int sweep = 0; sweep < kSchurSweeps && nb > 0; ++sweep) {
    double largest_change = 0.0, largest = 0.0;
    for (int b = 0; b < nb; ++b) {
      const double diagonal = schur_[b * K + b];
      // Only a row the rest hold entirely is left out: skipping rows the rest hold
      // nearly (a diagonal under 1e-11 of A's) let the MTM and SUJ, loaded overlapping,
      // throw each other metres (islands_test).
      if (!(diagonal > 0)) continue;
      double sum = reduced_rhs_[b];
      for (int c = 0; c < nb; ++c) sum -= schur_[b * K + c] * x[c];
      const Row& row = row_[bounded_[b]];
      double low = row.row->m_lowerLimit, high = row.row->m_upperLimit;
      if (row.normal >= 0) {  // friction: within the coefficient times the contact's push
        const int contact = bounded_slot_[row.normal];
        const double push =
            row_[row.normal].row->m_appliedImpulse + (contact >= 0 ? x[contact] : 0.0);
        high = row.row->m_friction * std::max(push, 0.0);
        if (row.rolling) high = std::min(high, double{row.row->m_friction});  // as Bullet caps it
        low = -high;
      }
      const double applied = row.row->m_appliedImpulse;
      const double next = std::clamp(x[b] + sum / diagonal, low - applied, high - applied);
      largest_change = std::max(largest_change, std::abs(next - x[b]));
      largest = std::max(largest, std::abs(next));
      x[b] = next;
    }
    if (largest_change <= 1e-12 * (1.0 + largest)) break;
  }
  // The equality rows answer the bounded rows' impulses: y - W^T x.
  for (int b = 0; b < nb; ++b)
    for (int k = 0; k < ne; ++k) y[k] -= w_[b * K + k] * x[b];

  for (int k = 0; k < ne; ++k)
    if (!std::isfinite(y[k])) return false;
  for (int b = 0; b < nb; ++b)
    if (!std::isfinite(x[b])) return false;
  auto apply = [&](int i, double impulse) {
    btSolverConstraint& row = *row_[i].row;
    row.m_appliedImpulse = row.m_appliedImpulse + impulse;
    btSolverBody& a = m_tmpSolverBodyPool[row.m_solverBodyIdA];
    btSolverBody& b = m_tmpSolverBodyPool[row.m_solverBodyIdB];
    a.internalApplyImpulse(row.m_contactNormal1 * a.internalGetInvMass(), row.m_angularComponentA,
                           impulse);
    b.internalApplyImpulse(row.m_contactNormal2 * b.internalGetInvMass(), row.m_angularComponentB,
                           impulse);
  };
  for (int k = 0; k < ne; ++k) apply(equality_[k], y[k]);
  for (int b = 0; b < nb; ++b) apply(bounded_[b], x[b]);
  return true;
}

}  // namespace afhub::physics
