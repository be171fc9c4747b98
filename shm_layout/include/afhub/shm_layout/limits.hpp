// Capacities of every payload, and what one file a user writes may cost to read.
// Payloads live in shared memory mapped at a different address in each process, so
// nothing in them may grow once loaned: each bound is chosen here once, with the
// reason beside it. Body states, body commands and the catalog are loaned at their
// real size (their variable arrays come last and only the counted entries are sent),
// so a large bound costs nothing until a model uses it.
#pragma once

#include <cstddef>
#include <cstdint>

namespace afhub {

// Descendant joints reported by one body. AMBF reports every joint below a body and
// has no limit: its rope environment has 72 joints below the root, and generated
// chains have hundreds. A state is loaned at its real size (about 24 bytes per
// joint), so this bound is far beyond real models: a state of 1024 joints is 25 KB.
inline constexpr std::size_t kMaxJointsPerBody = 1024;

// A body's channel name "<namespace>/<body>" is an iceoryx instance string,
// which holds at most 100 characters. The buffer keeps a terminating NUL.
inline constexpr std::size_t kMaxChannelNameLength = 100;
inline constexpr std::size_t kChannelNameBufferSize = 104;

// Joint names in AMBF models are short identifiers ("baselink-link1"); 63 characters
// covers generated names with namespaces while keeping a catalog entry near 4 KB.
inline constexpr std::size_t kMaxJointNameLength = 63;
inline constexpr std::size_t kJointNameBufferSize = 64;

// Process (iceoryx runtime) names are limited to 100 characters by iceoryx.
inline constexpr std::size_t kProcessNameBufferSize = 104;

// Bodies in the catalog. Their states and commands are slots in blocks (slot_block.hpp),
// a publisher port per block rather than per body, so iceoryx's 512 ports no longer
// bound them; the catalog does: a catalog of this many bodies (with 8192 joint names)
// is a 1.8 MB chunk, of which the hub keeps 24 (hub_mempools.cpp).
inline constexpr std::size_t kMaxBodies = 4096;

// Bodies (rigid and soft, passive ones too) one physics simulates. Passive bodies use
// no hub resource, so this bounds what a model costs to build and step: Bullet keeps
// per body its shapes, pairs and manifolds, and a step visits every body. Twice the
// largest scene measured (8000 bodies, tests/physics/scene_benchmark.cpp). Checked
// from the files' body lists, before a body is read.
inline constexpr std::size_t kMaxModelBodies = 16384;

// Bodies in a scene description (passive ones too, which publish no state): a body
// entry is about 1.4 KB, so the largest scene is under 1 MB. Bodies past it are
// left out of the scene (not drawn) and said once by the physics.
inline constexpr std::size_t kMaxSceneBodies = 512;

// Joint positions a viewer's pose feed carries (ScenePoses): each body's joints below
// it, so a chain of n links carries about n^2/2. Bodies past it show no joints.
inline constexpr std::size_t kMaxSceneJointValues = 16384;

// Soft bodies a scene description lists (AMBF's models have none to a few).
inline constexpr std::size_t kMaxSceneSoftBodies = 16;

// Nodes and faces of one soft body a viewer draws. A node travels at display rate as
// 12 bytes, so 4096 nodes are a 48 KB chunk; a closed surface has about twice as many
// faces as nodes. A soft body with more is refused at load, naming its file.
inline constexpr std::size_t kMaxSoftBodyNodes = 4096;
inline constexpr std::size_t kMaxSoftBodyFaces = 8192;

// Joint names in the catalog: every distinct name once, and per body a list of
// indices into them (a chain of N links, every link active, lists N^2/2 indices but
// N names). Loaned at the real size, so these bound only what a faulty writer claims.
inline constexpr std::size_t kMaxCatalogJointNames = 1 << 16;
inline constexpr std::size_t kMaxCatalogJointRefs = 1 << 20;

// Proximity-sensor rays reported in one body's state (AMBF's parametric sensors
// are resolution^2 rays; 32 covers a 5x5 grid and several small arrays).
inline constexpr std::size_t kMaxSensorRaysPerBody = 32;

// Constraint actuators one body command can drive.
inline constexpr std::size_t kMaxActuatorsPerBody = 8;

// Steps one `world step N` may ask for while paused: 1000 s at 1 kHz. Longer runs are
// a resume; a world that steps for hours while it says "paused" misleads every reader.
inline constexpr std::uint32_t kMaxWorldStepsPerCommand = 1'000'000;

// A held pause's longest silence (WorldCommand.hold_ms): a minute. A holder quiet for
// longer is gone, not computing.
inline constexpr std::uint32_t kMaxPauseHoldMs = 60'000;
// Processes holding one pause together (several throttling scripts on one world); a
// further one takes the place of the hold lapsing soonest.
inline constexpr std::size_t kMaxPauseHolders = 8;

// The longest a world command's sender may wait for it (WorldCommand.valid_ms): an
// hour, `afhub world --timeout`'s bound.
inline constexpr std::uint32_t kMaxWorldCommandValidMs = 3'600'000;
// A command read just before its valid_ms ends is acted on in that cycle: its sender
// reads the world states this much longer (a cycle is a millisecond; loaded, tens).
inline constexpr std::int64_t kWorldCommandShownWithinNs = 200'000'000;

// Lights and cameras whose poses the world state carries.
inline constexpr std::size_t kMaxWorldObjects = 8;

// Processes attached to one hub: iceoryx 2.0 allows 300 runtimes (MAX_PROCESS_NUMBER),
// the hub's among them. Each publishes a body directory: their pool is sized for all.
inline constexpr std::size_t kMaxProcesses = 300;

// Readers of one channel: iceoryx 2.0 connects at most 256 subscribers to a publisher
// (IOX_MAX_SUBSCRIBERS_PER_PUBLISHER). Every client reads the hub's catalog, so the
// 257th client finds no room; it is told so.
inline constexpr std::size_t kMaxReadersPerChannel = 256;

// Processes listed in the hub's health: all of them (112 bytes each).
inline constexpr std::size_t kMaxHealthProcesses = kMaxProcesses;

// iceoryx 2.0 supports at most 32 mempools per segment.
inline constexpr std::size_t kMaxMempools = 32;

// What one YAML file (a model, a world, an input device or bridge config) may cost.
// yaml-cpp builds a whole file as a tree of about 450 bytes and 2 us per node: a
// 50 MB file of 25 million values took 11 GB and 49 s. Files are scanned first,
// without the tree, and refused at the first node past a bound. The largest real
// AMBF models have 2300 nodes, nest 5 deep and weigh 16 KB; generated ones with the
// hub's kMaxBodies active bodies and thousands of passive ones stay far below these.
// A file's bytes: read whole before parsing, so this also bounds its copy in memory.
inline constexpr std::uintmax_t kMaxYamlFileBytes = 16u << 20;
// Values, lists and maps in one file (an alias counts the nodes it repeats): at most
// about 0.5 GB and 2 s of yaml-cpp's tree (measured: 0.57 GB).
inline constexpr std::size_t kMaxYamlNodes = 1'000'000;
// Lists and maps inside each other: every reader walks them recursively.
inline constexpr std::size_t kMaxYamlDepth = 64;

}  // namespace afhub
