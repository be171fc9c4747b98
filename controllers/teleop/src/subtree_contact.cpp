// Contact wrenches of a multibody summed at its root (see subtree_contact.hpp).
#include "afhub/teleop/subtree_contact.hpp"

namespace afhub::teleop {

Wrench subtree_contact_wrench(const Vec3& origin_m,
                              std::span<const BodyState* const> bodies) noexcept {
  Wrench sum;
  for (const BodyState* body : bodies) {
    if (!body) continue;
    const Vec3& f = body->contact_wrench.force_n;
    const Vec3& t = body->contact_wrench.torque_nm;
    const Vec3& p = body->pose.position_m;
    const Vec3 r{p.x - origin_m.x, p.y - origin_m.y, p.z - origin_m.z};
    sum.force_n = {sum.force_n.x + f.x, sum.force_n.y + f.y, sum.force_n.z + f.z};
    sum.torque_nm = {sum.torque_nm.x + t.x + (r.y * f.z - r.z * f.y),
                     sum.torque_nm.y + t.y + (r.z * f.x - r.x * f.z),
                     sum.torque_nm.z + t.z + (r.x * f.y - r.y * f.x)};
  }
  return sum;
}

}  // namespace afhub::teleop
