// The contact wrench on a whole multibody, gathered at its root: what contact feedback
// renders, so that a finger touching the floor is felt as well as the palm.
#pragma once

#include <span>

#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/geometry.hpp"

namespace afhub::teleop {

// The sum of the bodies' contact wrenches (BodyState.contact_wrench: world frame, the
// torque about each body's own origin), the torque moved to `origin_m` (the root's
// origin): each body's adds (its origin - origin_m) x its force. Null entries (a body
// with no state yet) add nothing. Contacts between two of the bodies cancel out.
Wrench subtree_contact_wrench(const Vec3& origin_m,
                              std::span<const BodyState* const> bodies) noexcept;

}  // namespace afhub::teleop
