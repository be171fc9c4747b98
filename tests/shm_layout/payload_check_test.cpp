// Payload validation: what a reader refuses before reading anything.
#include "afhub/shm_layout/payload_check.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <memory>
#include <tuple>
#include <vector>

#include "afhub/shm_layout/layout_id.hpp"
#include "afhub/shm_layout/packed_body_state.hpp"
#include "afhub/shm_layout/world_control.hpp"

namespace afhub {
namespace {

template <class T>
T stamped(PayloadKind kind) {
  T payload{};
  payload.header.layout_id = kLayoutId;
  payload.header.kind = kind;
  return payload;
}

TEST(PayloadCheck, AcceptsAPayloadOfThisBuild) {
  auto state = stamped<BodyState>(PayloadKind::kBodyState);
  state.joint_count = kMaxJointsPerBody;
  EXPECT_EQ(check_payload(&state, sizeof state, PayloadKind::kBodyState), PayloadError::kNone);
}

TEST(PayloadCheck, RefusesAForeignLayout) {
  auto state = stamped<BodyState>(PayloadKind::kBodyState);
  state.header.layout_id = kLayoutId ^ 1;
  EXPECT_EQ(check_payload(&state, sizeof state, PayloadKind::kBodyState),
            PayloadError::kForeignLayout);
}

TEST(PayloadCheck, RefusesAnotherPayloadKind) {
  auto command = stamped<BodyCommand>(PayloadKind::kBodyCommand);
  EXPECT_EQ(check_payload(&command, sizeof command, PayloadKind::kBodyState),
            PayloadError::kWrongKind);
}

TEST(PayloadCheck, RefusesAChunkShorterThanItsPayload) {
  auto state = stamped<BodyState>(PayloadKind::kBodyState);
  EXPECT_EQ(check_payload(&state, body_state_bytes(0) - 8, PayloadKind::kBodyState),
            PayloadError::kTooSmall);
  EXPECT_EQ(check_payload(&state, sizeof(PayloadHeader) - 1, PayloadKind::kBodyState),
            PayloadError::kTooSmall);
}

// States and commands are sent at their real size: a count beyond the chunk's
// joints is refused, naming the count, as one beyond capacity is.
TEST(PayloadCheck, SizedPayloadsHoldTheirCountedJoints) {
  const char* field = nullptr;
  auto state = stamped<BodyState>(PayloadKind::kBodyState);
  state.joint_count = 200;
  EXPECT_EQ(check_payload(&state, body_state_bytes(200), PayloadKind::kBodyState),
            PayloadError::kNone);
  EXPECT_EQ(check_payload(&state, body_state_bytes(200) - 1, PayloadKind::kBodyState, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "BodyState.joint_count");
  auto command = stamped<BodyCommand>(PayloadKind::kBodyCommand);
  command.joint_count = 200;
  EXPECT_EQ(check_payload(&command, body_command_bytes(200), PayloadKind::kBodyCommand),
            PayloadError::kNone);
  EXPECT_EQ(check_payload(&command, body_command_bytes(199), PayloadKind::kBodyCommand, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "BodyCommand.joint_count");
}

TEST(PayloadCheck, RefusesJointCountsBeyondCapacity) {
  auto state = stamped<BodyState>(PayloadKind::kBodyState);
  state.joint_count = kMaxJointsPerBody + 1;
  EXPECT_EQ(check_payload(&state, sizeof state, PayloadKind::kBodyState),
            PayloadError::kCountTooLarge);
  auto command = stamped<BodyCommand>(PayloadKind::kBodyCommand);
  command.joint_count = kMaxJointsPerBody + 1;
  EXPECT_EQ(check_payload(&command, sizeof command, PayloadKind::kBodyCommand),
            PayloadError::kCountTooLarge);
}

TEST(PayloadCheck, BodyListsMustHoldTheBodiesTheyCount) {
  std::vector<unsigned char> bytes(body_list_bytes(2));
  PayloadHeader header{kLayoutId, PayloadKind::kCatalog};
  std::memcpy(bytes.data(), &header, sizeof header);
  std::uint32_t count = 2;
  std::memcpy(bytes.data() + offsetof(BodyList, body_count), &count, sizeof count);
  EXPECT_EQ(check_payload(bytes.data(), bytes.size(), PayloadKind::kCatalog), PayloadError::kNone);
  count = 3;  // claims one more body than the chunk holds
  std::memcpy(bytes.data() + offsetof(BodyList, body_count), &count, sizeof count);
  EXPECT_EQ(check_payload(bytes.data(), bytes.size(), PayloadKind::kCatalog),
            PayloadError::kCountTooLarge);
}

// Every count a consumer indexes an array with is held to the array's capacity,
// and the refusal names the field.
template <class T>
void expect_count_refused(T payload, std::uint32_t T::*count, std::size_t capacity,
                          const char* field_name) {
  payload.*count = static_cast<std::uint32_t>(capacity);
  const char* field = "unset";
  EXPECT_EQ(check_payload(&payload, sizeof payload, T::kKind, &field), PayloadError::kNone)
      << field_name;
  EXPECT_STREQ(field, "");
  payload.*count = static_cast<std::uint32_t>(capacity + 1);
  EXPECT_EQ(check_payload(&payload, sizeof payload, T::kKind, &field), PayloadError::kCountTooLarge)
      << field_name;
  EXPECT_STREQ(field, field_name);
  payload.*count = 0xffffffffu;
  EXPECT_EQ(check_payload(&payload, sizeof payload, T::kKind), PayloadError::kCountTooLarge)
      << field_name;
}

TEST(PayloadCheck, RefusesEveryCountBeyondItsArray) {
  expect_count_refused(stamped<BodyState>(PayloadKind::kBodyState), &BodyState::joint_count,
                       kMaxJointsPerBody, "BodyState.joint_count");
  expect_count_refused(stamped<BodyState>(PayloadKind::kBodyState), &BodyState::sensor_ray_count,
                       kMaxSensorRaysPerBody, "BodyState.sensor_ray_count");
  expect_count_refused(stamped<BodyCommand>(PayloadKind::kBodyCommand), &BodyCommand::joint_count,
                       kMaxJointsPerBody, "BodyCommand.joint_count");
  expect_count_refused(stamped<BodyCommand>(PayloadKind::kBodyCommand),
                       &BodyCommand::actuator_count, kMaxActuatorsPerBody,
                       "BodyCommand.actuator_count");
  expect_count_refused(stamped<WorldState>(PayloadKind::kWorldState), &WorldState::light_count,
                       kMaxWorldObjects, "WorldState.light_count");
  expect_count_refused(stamped<WorldState>(PayloadKind::kWorldState), &WorldState::camera_count,
                       kMaxWorldObjects, "WorldState.camera_count");
  expect_count_refused(stamped<Health>(PayloadKind::kHealth), &Health::process_count,
                       kMaxHealthProcesses, "Health.process_count");
  expect_count_refused(stamped<Health>(PayloadKind::kHealth), &Health::mempool_count, kMaxMempools,
                       "Health.mempool_count");
}

TEST(PayloadCheck, RefusesAWorldStepOfNoneOrBeyondTheBound) {
  auto command = stamped<WorldCommand>(PayloadKind::kWorldCommand);
  command.action = WorldAction::kStep;
  const char* field = "unset";
  for (const std::uint32_t steps : {1u, kMaxWorldStepsPerCommand}) {
    command.step_count = steps;
    EXPECT_EQ(check_payload(&command, sizeof command, PayloadKind::kWorldCommand),
              PayloadError::kNone)
        << steps;
  }
  for (const std::uint32_t steps : {0u, kMaxWorldStepsPerCommand + 1, 0xffffffffu}) {
    command.step_count = steps;
    EXPECT_NE(check_payload(&command, sizeof command, PayloadKind::kWorldCommand, &field),
              PayloadError::kNone)
        << steps;
    EXPECT_STREQ(field, "WorldCommand.step_count");
  }
  command.action = WorldAction::kPause;  // the count means nothing to a pause
  EXPECT_EQ(check_payload(&command, sizeof command, PayloadKind::kWorldCommand),
            PayloadError::kNone);
}

TEST(PayloadCheck, RefusesAnUnknownWorldActionAndAHoldBeyondAMinute) {
  auto command = stamped<WorldCommand>(PayloadKind::kWorldCommand);
  command.action = WorldAction::kPause;
  command.hold_ms = kMaxPauseHoldMs;
  const char* field = "unset";
  // A hold with no holder to renew it.
  EXPECT_NE(check_payload(&command, sizeof command, PayloadKind::kWorldCommand, &field),
            PayloadError::kNone);
  EXPECT_STREQ(field, "WorldCommand.hold_ms");
  command.header.publisher_pid = 42;
  EXPECT_EQ(check_payload(&command, sizeof command, PayloadKind::kWorldCommand, &field),
            PayloadError::kNone)
      << field;
  command.hold_ms = kMaxPauseHoldMs + 1;
  EXPECT_NE(check_payload(&command, sizeof command, PayloadKind::kWorldCommand, &field),
            PayloadError::kNone);
  EXPECT_STREQ(field, "WorldCommand.hold_ms");
  command.hold_ms = 0;
  command.action = static_cast<WorldAction>(6);
  EXPECT_NE(check_payload(&command, sizeof command, PayloadKind::kWorldCommand, &field),
            PayloadError::kNone);
  EXPECT_STREQ(field, "WorldCommand.action");
}

TEST(WorldControl, PauseEndsTheStepsStillToRunAndStepsAreBounded) {
  WorldControl control;
  WorldCommand command;
  command.action = WorldAction::kPause;
  control.apply(command, 0);
  EXPECT_TRUE(control.halted());
  command.action = WorldAction::kStep;
  command.step_count = 3;
  control.apply(command, 0);
  EXPECT_FALSE(control.halted()) << "a world running its steps is not standing still";
  EXPECT_TRUE(control.take_step());
  command.action = WorldAction::kPause;
  control.apply(command, 0);
  EXPECT_TRUE(control.halted());
  EXPECT_FALSE(control.take_step()) << "the pause did not stop the steps in progress";
  // Steps asked for one after another never add up past the bound.
  command.action = WorldAction::kStep;
  command.step_count = kMaxWorldStepsPerCommand;
  control.apply(command, 0);
  control.apply(command, 0);
  EXPECT_EQ(control.steps_to_run, kMaxWorldStepsPerCommand);
}

// A held pause lasts while its holder's commands keep coming within the hold, and
// lapses (the world runs on) once they stop; a plain pause never lapses.
TEST(WorldControl, AHeldPauseLapsesOnceItsHolderIsQuiet) {
  constexpr std::int64_t kMs = 1'000'000;
  WorldControl control;
  WorldCommand hold;
  hold.header.publisher_pid = 42;
  hold.action = WorldAction::kPause;
  hold.hold_ms = 500;
  control.apply(hold, 0);
  EXPECT_TRUE(control.halted());
  EXPECT_EQ(control.lapse(500 * kMs).pid, 0u) << "lapsed at its hold, not after it";
  // Any command of the holder's renews it: a step, or a word that does nothing.
  WorldCommand word = hold;
  word.action = WorldAction::kNone;
  control.apply(word, 400 * kMs);
  WorldCommand step = hold;
  step.action = WorldAction::kStep;
  control.apply(step, 800 * kMs);
  EXPECT_TRUE(control.take_step());
  EXPECT_EQ(control.lapse(1200 * kMs).pid, 0u);
  // Another process's commands do not (one without a hold of its own).
  WorldCommand other = word;
  other.header.publisher_pid = 43;
  other.hold_ms = 0;
  control.apply(other, 1250 * kMs);
  EXPECT_EQ(control.lapse(1301 * kMs).pid, 42u);
  EXPECT_FALSE(control.paused) << "the world did not run on";
  EXPECT_EQ(control.lapse(5000 * kMs).pid, 0u) << "said twice";

  // A plain pause, a user's, takes over a held one and holds until resumed.
  control.apply(hold, 0);
  WorldCommand plain = other;
  plain.action = WorldAction::kPause;
  plain.hold_ms = 0;
  control.apply(plain, 100 * kMs);
  EXPECT_EQ(control.lapse(60'000 * kMs).pid, 0u);
  EXPECT_TRUE(control.paused);
  // A resume ends a hold: nothing lapses later.
  control.apply(hold, 0);
  WorldCommand resume = hold;
  resume.action = WorldAction::kResume;
  control.apply(resume, 10 * kMs);
  EXPECT_EQ(control.lapse(60'000 * kMs).pid, 0u);
  // Nor does a held pause make a plain one lapse (`afhub world pause`, then a throttling
  // script that dies).
  control.apply(plain, 0);
  control.apply(hold, 0);
  EXPECT_EQ(control.lapse(60'000 * kMs).pid, 0u);
  EXPECT_TRUE(control.paused);
}

// Several holders hold one pause: it lasts while one of them is not quiet, and each
// releases its own hold (a throttling script that ends); a plain pause stays.
TEST(WorldControl, HeldPausesAddUpAndEachHolderReleasesItsOwn) {
  constexpr std::int64_t kMs = 1'000'000;
  const auto command = [](std::uint32_t pid, WorldAction action, std::uint32_t hold_ms = 0) {
    WorldCommand made;
    made.header.publisher_pid = pid;
    made.action = action;
    made.hold_ms = hold_ms;
    return made;
  };
  const WorldCommand a_holds = command(42, WorldAction::kPause, 500);
  const WorldCommand b_holds = command(43, WorldAction::kPause, 500);
  const WorldCommand a_renews = command(42, WorldAction::kNone);
  const WorldCommand a_releases = command(42, WorldAction::kRelease);
  const WorldCommand b_releases = command(43, WorldAction::kRelease);
  WorldControl control;
  control.apply(a_holds, 0);
  control.apply(b_holds, 100 * kMs);
  control.apply(a_renews, 400 * kMs);
  EXPECT_FALSE(control.lapse(700 * kMs)) << "B went quiet while A holds";
  EXPECT_TRUE(control.paused);
  EXPECT_EQ(control.paused_by_pid, 42u);
  control.apply(a_renews, 800 * kMs);
  const WorldControl::Lapsed lapsed = control.lapse(1301 * kMs);
  EXPECT_EQ(lapsed.pid, 42u);
  EXPECT_EQ(lapsed.hold_ms, 500u);
  EXPECT_FALSE(control.paused);

  // A release ends its sender's hold alone.
  control.apply(a_holds, 0);
  control.apply(b_holds, 0);
  control.apply(b_releases, 0);
  EXPECT_TRUE(control.paused) << "A still holds it";
  EXPECT_EQ(control.paused_by_pid, 42u);
  control.apply(a_releases, 0);
  EXPECT_FALSE(control.paused);
  control.apply(a_releases, 0);
  EXPECT_FALSE(control.paused) << "a release paused a running world";
  // A user's plain pause stays when the holders release.
  control.apply(a_holds, 0);
  control.apply(command(7, WorldAction::kPause), 0);
  control.apply(a_releases, 0);
  EXPECT_TRUE(control.paused);
  EXPECT_EQ(control.paused_by_pid, 7u);
  // Even when the release comes from the plain pause's own pid (a DDS bridge carries both
  // a user's pause and a script's release).
  control.apply(command(7, WorldAction::kRelease), 0);
  EXPECT_TRUE(control.paused) << "a release ended a plain pause";

  // A holder stalled past its hold while another held the pause takes it again with its
  // next renewal, and holds once the other goes.
  control.apply(command(7, WorldAction::kResume), 0);
  control.apply(a_holds, 0);
  control.apply(b_holds, 0);
  control.apply(command(43, WorldAction::kNone), 400 * kMs);
  EXPECT_FALSE(control.lapse(600 * kMs)) << "B holds";
  WorldCommand a_renews_holding = a_renews;
  a_renews_holding.hold_ms = 500;
  control.apply(a_renews_holding, 700 * kMs);
  control.apply(b_releases, 800 * kMs);
  EXPECT_TRUE(control.paused) << "A's renewal did not take its hold again";
  EXPECT_EQ(control.paused_by_pid, 42u);
  // Such a renewal does not pause a running world.
  control.apply(a_releases, 900 * kMs);
  control.apply(a_renews_holding, 950 * kMs);
  EXPECT_FALSE(control.paused);

  // Past kMaxPauseHolders, a new holder takes the place of the hold lapsing soonest.
  control.apply(command(7, WorldAction::kResume), 0);
  for (std::uint32_t pid = 100; pid < 100 + kMaxPauseHolders + 1; ++pid)
    control.apply(command(pid, WorldAction::kPause, 1000), pid * kMs);
  const auto holds = [&](std::uint32_t pid) {
    return std::any_of(control.holds.begin(), control.holds.end(),
                       [&](const WorldControl::Hold& hold) { return hold.pid == pid; });
  };
  const std::uint32_t last = 100 + kMaxPauseHolders;
  EXPECT_FALSE(holds(100)) << "the hold lapsing soonest kept its place";
  EXPECT_TRUE(holds(last));
  EXPECT_FALSE(control.lapse((last + 1000) * kMs)) << "lapsed while the last one holds";
  EXPECT_EQ(control.lapse((last + 1000) * kMs + 1).pid, last) << "the last to go quiet is said";
}

// The world state names whose pause is in force, and whether it is held.
TEST(WorldControl, TheWorldStateSaysWhosePauseIsInForce) {
  WorldControl control;
  WorldState world;
  WorldCommand plain;
  plain.header.publisher_pid = 7;
  plain.action = WorldAction::kPause;
  WorldCommand hold = plain;
  hold.header.publisher_pid = 42;
  hold.hold_ms = 500;
  WorldCommand resume = plain;
  resume.action = WorldAction::kResume;
  const auto said = [&] {
    control.describe_pause(world);
    return std::tuple(world.paused != 0, world.paused_by_pid, world.pause_held != 0);
  };
  EXPECT_EQ(said(), std::tuple(false, 0u, false));
  control.apply(hold, 0);
  EXPECT_EQ(said(), std::tuple(true, 42u, true));
  control.apply(plain, 0);  // takes the held one over
  EXPECT_EQ(said(), std::tuple(true, 7u, false));
  control.apply(hold, 0);  // the plain one stays in force
  EXPECT_EQ(said(), std::tuple(true, 7u, false));
  control.apply(resume, 0);
  EXPECT_EQ(said(), std::tuple(false, 0u, false));
  control.apply(hold, 0);
  control.lapse(600'000'000);
  EXPECT_EQ(said(), std::tuple(false, 0u, false)) << "a lapsed pause still named";
}

TEST(PayloadCheck, RefusesABodyListWhoseBodyCountsTooManyJoints) {
  for (auto kind : {PayloadKind::kBodyDirectory, PayloadKind::kCatalog}) {
    auto list = std::make_unique<BodyList>();
    // Published with its two bodies, one joint name and kMaxJointsPerBody references.
    const std::size_t bytes = body_list_bytes(2, 1, kMaxJointsPerBody);
    list->header = PayloadHeader{kLayoutId, kind};
    list->body_count = 2;
    list->joint_name_count = 1;
    list->joint_ref_count = kMaxJointsPerBody;
    list->bodies[1].joint_count = kMaxJointsPerBody;
    EXPECT_EQ(check_payload(list.get(), bytes, kind), PayloadError::kNone);
    list->bodies[1].joint_count = kMaxJointsPerBody + 1;
    const char* field = nullptr;
    EXPECT_EQ(check_payload(list.get(), bytes, kind, &field), PayloadError::kCountTooLarge);
    EXPECT_STREQ(field, "BodyInfo.joint_count");
    // Its references past the list's, a reference past the names, counts past the chunk.
    list->bodies[1].joint_count = 2;
    list->bodies[1].first_joint_ref = kMaxJointsPerBody - 1;
    EXPECT_EQ(check_payload(list.get(), bytes, kind, &field), PayloadError::kCountTooLarge);
    EXPECT_STREQ(field, "BodyInfo.first_joint_ref");
    list->bodies[1].first_joint_ref = 0;
    EXPECT_EQ(check_payload(list.get(), bytes, kind), PayloadError::kNone);
    joint_refs_in(*list)[5] = 1;
    EXPECT_EQ(check_payload(list.get(), bytes, kind, &field), PayloadError::kCountTooLarge);
    EXPECT_STREQ(field, "BodyList joint reference");
    joint_refs_in(*list)[5] = 0;
    EXPECT_EQ(check_payload(list.get(), bytes - 4, kind, &field), PayloadError::kCountTooLarge);
    EXPECT_STREQ(field, "BodyList.joint_ref_count");
    // Its sensors', actuators', children's and parent's references follow its joints'.
    list->bodies[1].sensor_ray_count = 3;
    list->bodies[1].actuator_count = 2;
    list->bodies[1].child_count = 4;
    list->bodies[1].parent_count = 1;
    EXPECT_EQ(check_payload(list.get(), bytes, kind), PayloadError::kNone);
    list->bodies[1].first_joint_ref = kMaxJointsPerBody - 11;  // 12 refs, 11 left
    EXPECT_EQ(check_payload(list.get(), bytes, kind, &field), PayloadError::kCountTooLarge);
    EXPECT_STREQ(field, "BodyInfo.first_joint_ref");
    list->bodies[1].first_joint_ref = 0;
    list->bodies[1].sensor_ray_count = kMaxSensorRaysPerBody + 1;
    EXPECT_EQ(check_payload(list.get(), bytes, kind, &field), PayloadError::kCountTooLarge);
    EXPECT_STREQ(field, "BodyInfo.sensor_ray_count");
    list->bodies[1].sensor_ray_count = 0;
    list->bodies[1].actuator_count = kMaxActuatorsPerBody + 1;
    EXPECT_EQ(check_payload(list.get(), bytes, kind, &field), PayloadError::kCountTooLarge);
    EXPECT_STREQ(field, "BodyInfo.actuator_count");
    list->bodies[1].actuator_count = 0;
    list->bodies[1].parent_count = 2;
    EXPECT_EQ(check_payload(list.get(), bytes, kind, &field), PayloadError::kCountTooLarge);
    EXPECT_STREQ(field, "BodyInfo.parent_count");
  }
}

TEST(PayloadCheck, SceneDescriptionsHoldTheirBodiesAndTerminateTheirPaths) {
  auto scene = std::make_unique<SceneDescription>();
  scene->header = PayloadHeader{kLayoutId, PayloadKind::kSceneDescription};
  scene->body_count = 2;
  std::size_t bytes = scene_description_bytes(2);
  const char* field = nullptr;
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription), PayloadError::kNone);
  // More bodies than the chunk holds, or than any scene may.
  EXPECT_EQ(check_payload(scene.get(), bytes - 1, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneDescription.body_count");
  scene->body_count = kMaxSceneBodies + 1;
  EXPECT_EQ(check_payload(scene.get(), sizeof *scene, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneDescription.body_count");
  scene->body_count = 2;
  // A path a viewer would read past: no terminating NUL.
  scene->bodies[1].mesh.fill('a');
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneBody.mesh");
  scene->bodies[1].mesh.fill('\0');
  scene->bodies[0].channel.fill('x');
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneBody.channel");
  scene->bodies[0].channel.fill('\0');
  scene->bodies[0].shape_count = kMaxSceneShapesPerBody + 1;
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneBody.shape_count");
  scene->bodies[0].shape_count = 0;
  // Further meshes: within their capacity, each of a listed body, its path terminated.
  scene->mesh_part_count = 1;
  scene->mesh_parts[0].body = 1;
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription), PayloadError::kNone);
  const std::pair<std::function<void()>, const char*> bad_parts[] = {
      {[&] { scene->mesh_part_count = kMaxSceneMeshParts + 1; },
       "SceneDescription.mesh_part_count"},
      {[&] { scene->mesh_parts[0].body = 2; }, "SceneMeshPart.body"},
      {[&] { scene->mesh_parts[0].mesh.fill('m'); }, "SceneMeshPart.mesh"}};
  for (const auto& [spoil, name] : bad_parts) {
    spoil();
    EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
              PayloadError::kCountTooLarge);
    EXPECT_STREQ(field, name);
    scene->mesh_part_count = 1;
    scene->mesh_parts[0] = SceneMeshPart{};
  }
  scene->mesh_part_count = 0;
  scene->camera_count = kMaxWorldObjects + 1;
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneDescription.camera_count");
  scene->camera_count = 1;
  scene->cameras[0].name.fill('c');
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneView.name");
  scene->cameras[0].name.fill('\0');
  scene->cameras[0].key.fill('k');
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneView.key");
  scene->cameras[0].key.fill('\0');
  scene->soft_body_count = kMaxSceneSoftBodies + 1;
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneDescription.soft_body_count");
  scene->soft_body_count = 1;
  scene->soft_bodies[0].channel.fill('s');
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneSoftBody.channel");
  scene->soft_bodies[0].channel.fill('\0');
  // The model files a recording names.
  scene->model_file_count = kMaxSceneModelFiles + 1;
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneDescription.model_file_count");
  scene->model_file_count = 1;
  scene->model_files[0].fill('/');
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneDescription.model_files");
  scene->model_file_count = 0;
  // The model folders a viewer serves meshes from.
  scene->model_folder_count = kMaxSceneModelFolders + 1;
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneDescription.model_folder_count");
  scene->model_folder_count = 1;
  scene->model_folders[0].fill('/');
  EXPECT_EQ(check_payload(scene.get(), bytes, PayloadKind::kSceneDescription, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SceneDescription.model_folders");
}

TEST(PayloadCheck, SoftBodyMeshesHoldTheirNodesAndFaces) {
  auto mesh = std::make_unique<SoftBodyMesh>();
  mesh->header = PayloadHeader{kLayoutId, PayloadKind::kSoftBodyMesh};
  mesh->node_count = 3;
  mesh->face_count = 1;
  mesh->faces[0] = {0, 1, 2};
  const std::size_t bytes = soft_body_mesh_bytes(1);
  const char* field = nullptr;
  EXPECT_EQ(check_payload(mesh.get(), bytes, PayloadKind::kSoftBodyMesh, &field),
            PayloadError::kNone);
  // More nodes than a soft body may have.
  mesh->node_count = kMaxSoftBodyNodes + 1;
  EXPECT_EQ(check_payload(mesh.get(), bytes, PayloadKind::kSoftBodyMesh, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SoftBodyMesh.node_count");
  mesh->node_count = 3;
  // More faces than the chunk holds, or than any soft body may.
  EXPECT_EQ(check_payload(mesh.get(), bytes - 1, PayloadKind::kSoftBodyMesh, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SoftBodyMesh.face_count");
  mesh->face_count = kMaxSoftBodyFaces + 1;
  EXPECT_EQ(check_payload(mesh.get(), sizeof *mesh, PayloadKind::kSoftBodyMesh, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SoftBodyMesh.face_count");
  mesh->face_count = 1;
  // A face naming a node the mesh does not have: a viewer would index past them.
  mesh->faces[0] = {0, 1, 3};
  EXPECT_EQ(check_payload(mesh.get(), bytes, PayloadKind::kSoftBodyMesh, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "SoftBodyMesh.faces");
}

TEST(PayloadCheck, ScenePosesHoldTheirBodiesAndJointValues) {
  auto poses = std::make_unique<ScenePoses>();
  poses->header = PayloadHeader{kLayoutId, PayloadKind::kScenePoses};
  poses->body_count = 2;
  poses->joint_value_count = 3;
  poses->bodies[0] = {{}, {0, 0, 0, 1}, 0, 3};
  poses->bodies[1] = {{}, {0, 0, 0, 1}, 3, 0};
  const std::size_t bytes = scene_poses_bytes(2, 3);
  const char* field = nullptr;
  EXPECT_EQ(check_payload(poses.get(), bytes, PayloadKind::kScenePoses, &field),
            PayloadError::kNone);
  // More bodies than the chunk holds, or than any scene may.
  EXPECT_EQ(check_payload(poses.get(), scene_poses_bytes(1), PayloadKind::kScenePoses, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "ScenePoses.body_count");
  poses->body_count = kMaxSceneBodies + 1;
  EXPECT_EQ(check_payload(poses.get(), sizeof *poses, PayloadKind::kScenePoses, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "ScenePoses.body_count");
  poses->body_count = 2;
  // More joint values than the chunk holds, or than any feed may.
  EXPECT_EQ(check_payload(poses.get(), bytes - 1, PayloadKind::kScenePoses, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "ScenePoses.joint_value_count");
  poses->joint_value_count = kMaxSceneJointValues + 1;
  EXPECT_EQ(check_payload(poses.get(), sizeof *poses, PayloadKind::kScenePoses, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "ScenePoses.joint_value_count");
  poses->joint_value_count = 3;
  // A body's joints past the values: a viewer would read beyond them.
  poses->bodies[1] = {{}, {0, 0, 0, 1}, 2, 2};
  EXPECT_EQ(check_payload(poses.get(), bytes, PayloadKind::kScenePoses, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "ScenePose.first_joint");
  poses->bodies[1] = {{}, {0, 0, 0, 1}, 0xFFFFFFFFU, 2};  // no wrap-around
  EXPECT_EQ(check_payload(poses.get(), bytes, PayloadKind::kScenePoses, &field),
            PayloadError::kCountTooLarge);
}

// A packed state (the step tape's form) is checked as a whole one is: its size must be
// one of the two its counts allow (with or without the reason), its reason terminated.
TEST(PayloadCheck, PackedStatesHoldWhatTheirCountsSay) {
  auto state = std::make_unique<BodyState>(stamped<BodyState>(PayloadKind::kBodyState));
  state->joint_count = 8;
  state->sensor_ray_count = 2;
  const auto packed = [&] {
    std::vector<std::uint8_t> bytes;
    for (const auto& piece : packed_pieces(*state))
      bytes.insert(bytes.end(), piece.begin(), piece.end());
    return bytes;
  };
  const char* field = nullptr;
  std::vector<std::uint8_t> bytes = packed();
  EXPECT_EQ(bytes.size(), packed_body_state_bytes(false, 2, 8));
  EXPECT_EQ(check_packed_body_state(bytes.data(), bytes.size(), &field), PayloadError::kNone);
  EXPECT_EQ(check_packed_body_state(bytes.data(), bytes.size() - 1, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "BodyState.joint_count");
  EXPECT_EQ(check_packed_body_state(bytes.data(), kPackedReasonAt - 1, &field),
            PayloadError::kTooSmall);
  // A whole state is not a packed one.
  EXPECT_EQ(check_packed_body_state(state.get(), body_state_bytes(8)),
            PayloadError::kCountTooLarge);

  std::memset(state->refusal_reason.data(), 'x', kRefusalReasonSize);  // unterminated
  bytes = packed();
  EXPECT_EQ(bytes.size(), packed_body_state_bytes(true, 2, 8));
  EXPECT_EQ(check_packed_body_state(bytes.data(), bytes.size(), &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "BodyState.refusal_reason");
  state->refusal_reason.back() = '\0';
  bytes = packed();
  EXPECT_EQ(check_packed_body_state(bytes.data(), bytes.size()), PayloadError::kNone);

  state->sensor_ray_count = kMaxSensorRaysPerBody + 1;
  EXPECT_EQ(check_packed_body_state(state.get(), kPackedReasonAt, &field),
            PayloadError::kCountTooLarge);
  EXPECT_STREQ(field, "BodyState.sensor_ray_count");
  state->sensor_ray_count = 0;
  state->header.layout_id ^= 1;
  EXPECT_EQ(check_packed_body_state(state.get(), kPackedReasonAt), PayloadError::kForeignLayout);
}

TEST(PayloadCheck, EveryErrorHasAnExplanation) {
  for (auto error : {PayloadError::kTooSmall, PayloadError::kForeignLayout,
                     PayloadError::kWrongKind, PayloadError::kCountTooLarge})
    EXPECT_GT(std::strlen(describe(error)), 30u);
}

TEST(Layout, PayloadsFitTheirMempoolsAndStaySmall) {
  // Sent at their real size: a body of up to 64 joints stays within 2 KB, the
  // contact wrench, the last refusal's sender and reason, its sensor rays' ranges and
  // the step its command in force answered (2536 B), and one of kMaxJointsPerBody
  // within the hub's largest body tier (hub_mempools.cpp).
  EXPECT_LE(body_state_bytes(64), 2048u + 56u + 168u + 8u * kMaxSensorRaysPerBody + 8u);
  EXPECT_LE(body_command_bytes(64), 1280u);
  EXPECT_EQ(body_state_bytes(kMaxJointsPerBody), sizeof(BodyState));
  EXPECT_LE(body_command_bytes(kMaxJointsPerBody), body_state_bytes(kMaxJointsPerBody));
  EXPECT_EQ(sizeof(PayloadHeader), 48u);
  // The largest scene description stays under 1 MB (hub_mempools.cpp holds it).
  EXPECT_LE(sizeof(SceneDescription), 1u << 20);
}

}  // namespace
}  // namespace afhub
