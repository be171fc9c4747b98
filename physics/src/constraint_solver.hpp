// The world's constraint solver: Bullet's sequential impulses (projected
// Gauss-Seidel) for islands without joints, with two changes.
// - Its work arrays are reserved up front: a scene that meets more contacts or
//   active limits than before does not allocate in the middle of a run.
// - An island of joints is solved directly. Gauss-Seidel converges slowly on a
//   closed loop whose links differ in mass by a thousand (a 2 g link on a 6 kg
//   body): at 20 iterations such loops opened by 40 to 150 mm under a 1 Hz drive.
//   Here every row of the island (joints, limits, motors, contacts and their
//   friction) is solved at once: a dense factorisation of the equality rows'
//   effective mass, the bounded rows through their Schur complement; the loops stay
//   shut to within the joints' error correction (tests/physics/closed_loop_test.cpp).
//   An open chain's rows meet only their neighbours', so its factor costs little:
//   125 eight-link arms took 1.3 ms of 20 iterations, directly a fraction of that
//   (tests/physics/physics_benchmark.cpp, docs/performance.md). An island of more
//   than kMaxDirectRows rows is iterated like the rest.
#pragma once

#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <btBulletDynamicsCommon.h>

#include <vector>

namespace afhub::physics {

class ConstraintSolver : public btMultiBodyConstraintSolver {
 public:
  // Mark a joint of an island of joints (user constraint type): one that holds a
  // closed loop, whose repeated rows the solve looks for, or a tree.
  static constexpr int kInLoopIsland = 0x4c4f4f50;
  static constexpr int kInTreeIsland = 0x54524545;
  // Past this, a dense solve costs more than a 1 kHz step has (256^3/6 multiply-adds
  // is about 3 M, a millisecond), and its matrices more memory than they are worth.
  static constexpr int kMaxDirectRows = 256;

  ConstraintSolver(int bodies, int joints);
  // Makes room for the direct solve (seven 256 x 256 matrices of doubles, 3.7 MB):
  // called at build when some constraint is marked, never in a step.
  void enable_direct_solve();

 protected:
  btScalar solveGroupCacheFriendlyIterations(btCollisionObject** bodies, int numBodies,
                                             btPersistentManifold** manifolds, int numManifolds,
                                             btTypedConstraint** constraints, int numConstraints,
                                             const btContactSolverInfo& info,
                                             btIDebugDraw* debug_drawer) override;

 private:
  // A row's Jacobian on one of its two bodies, and what a unit impulse of the row
  // does to that body's velocities (zero for a body that cannot move).
  struct Side {
    int body;  // solver body
    bool moves;
    btVector3 normal, turn;  // m_contactNormal1/2, m_relpos1/2CrossNormal
    btVector3 linear{0, 0, 0}, angular{0, 0, 0};
  };

  void factor(bool find_dependent) noexcept;
  void cholesky(const double* m, bool judge) noexcept;
  void solve_kept(double* v) const noexcept;
  void solve_equality(double* v) noexcept;
  bool solve_rows() noexcept;

  struct Row {
    btSolverConstraint* row;
    int normal;    // a friction row: its contact's row; else -1
    bool rolling;  // a rolling friction row
  };
  int body_capacity_;  // solver bodies a group may hold
  int rows_ = 0;
  std::vector<Row> row_;
  std::vector<int> bounded_slot_;  // per row: its place in bounded_, or -1
  std::vector<Side> sides_;        // per row side: 2 row + side
  // The row sides (2 row + side) meeting at each solver body, as lists: the first
  // per body, the next per side; -1 ends.
  std::vector<int> body_rows_, next_side_;
  std::vector<int> body_first_row_;      // per solver body: the first row meeting it
  std::vector<int> row_first_;           // per row: A's row is zero before this row
  std::vector<int> at_or_after_;         // per row: the first equality row at or after it
  std::vector<int> equality_, bounded_;  // row indices
  std::vector<bool> dependent_;          // per equality row: implied by the rows before it
  std::vector<int> first_;               // per equality row: its first nonzero in A
  std::vector<int> last_;                // per column of the factor: its last row
  int nulls_ = 0;                        // dependent equality rows
  // A's entry (i, j), from its lower triangle.
  double a(int i, int j) const noexcept {
    return i >= j ? a_[i * kMaxDirectRows + j] : a_[j * kMaxDirectRows + i];
  }

  // Dense, row-major, kMaxDirectRows wide: the rows' effective mass A and their
  // shape matrix (factor(): which rows a loop repeats is judged on it), both
  // symmetric and kept as their lower triangles (row >= column); the Cholesky
  // factor of its equality block's kept rows; the null vectors of the dependent
  // rows and their Gram matrix's factor; W = A_ee^+ A_eb; the bounded rows' Schur
  // complement S = A_bb - A_be W.
  std::vector<double> a_, shape_, factor_, null_, gram_, w_, schur_;
  std::vector<double> residual_, equality_solution_, bounded_solution_, reduced_rhs_, gram_rhs_;
};

}  // namespace afhub::physics
