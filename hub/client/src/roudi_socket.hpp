// Where iceoryx 2.0's RouDi answers, and the shared memory every runtime maps.
#pragma once

namespace afhub {

inline constexpr const char* kRoudiSocketPath =
    "/tmp/roudi";  // iceoryx 2.0: IOX_UDS_SOCKET_PATH_PREFIX + "roudi"
// iceoryx 2.0's management segment: every runtime maps it read-write.
inline constexpr const char* kManagementSegment = "/dev/shm/iceoryx_mgmt";

}  // namespace afhub
