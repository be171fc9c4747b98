/* A remote machine's stand-in for testing `afhub bridge dds`, on afhub's DDS types and
 * Cyclone alone (no afhub code):
 *   dds_peer [--bodies N] [--joints J] [--prefix P] [--state-rate HZ]
 *            [--command BODY --command-joints K] [--seconds S]
 * announces N bodies P0 .. P<N-1> (default 1, "peer/b") on afhub/body_info, each with
 * the J joint names j0 .. j<J-1> (default 1), as an exporting bridge does; publishes
 * their states at HZ (default 0: none); with --command, writes position commands of K
 * joints (default 1) to BODY at 500 Hz, as a mirroring bridge does; and counts the
 * states of other bodies it receives, and the commands to its own bodies (those named
 * P...). Each second it prints to stdout
 *   dds_peer: states received R, commands sent C, commands received K
 * for S seconds (default: until SIGTERM). Exit 0, 1 on bad usage, 2 on a DDS error. */
#include <dds/dds.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "afhub_dds.h"

static volatile sig_atomic_t stopping = 0;
static void on_signal(int sig) {
  (void)sig;
  stopping = 1;
}

static dds_entity_t must(dds_entity_t entity, const char* what) {
  if (entity < 0) {
    fprintf(stderr, "dds_peer: %s: %s\n", what, dds_strretcode(entity));
    exit(2);
  }
  return entity;
}

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static void usage(void) {
  fprintf(stderr,
          "usage: dds_peer [--bodies N] [--joints J] [--prefix P] [--state-rate HZ] "
          "[--command BODY --command-joints K] [--seconds S]\n");
  exit(1);
}

int main(int argc, char** argv) {
  unsigned bodies = 1, joints = 1, command_joints = 1;
  const char* prefix = "peer/b";
  const char* command_body = NULL;
  double state_rate = 0.0, seconds = 0.0;
  for (int i = 1; i < argc; ++i) {
    if (i + 1 >= argc) usage();
    if (!strcmp(argv[i], "--bodies"))
      bodies = (unsigned)atoi(argv[++i]);
    else if (!strcmp(argv[i], "--joints"))
      joints = (unsigned)atoi(argv[++i]);
    else if (!strcmp(argv[i], "--prefix"))
      prefix = argv[++i];
    else if (!strcmp(argv[i], "--state-rate"))
      state_rate = atof(argv[++i]);
    else if (!strcmp(argv[i], "--command"))
      command_body = argv[++i];
    else if (!strcmp(argv[i], "--command-joints"))
      command_joints = (unsigned)atoi(argv[++i]);
    else if (!strcmp(argv[i], "--seconds"))
      seconds = atof(argv[++i]);
    else
      usage();
  }
  if (joints > afhub_dds_kMaxJointNames || command_joints > afhub_dds_kMaxJoints) usage();
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);

  const dds_entity_t participant = must(dds_create_participant(0, NULL, NULL), "participant");
  const dds_entity_t info_topic =
      must(dds_create_topic(participant, &afhub_dds_BodyInfo_desc, "afhub/body_info", NULL, NULL),
           "info topic");
  const dds_entity_t state_topic =
      must(dds_create_topic(participant, &afhub_dds_BodyState_desc, "afhub/body_state", NULL, NULL),
           "state topic");
  const dds_entity_t command_topic = must(
      dds_create_topic(participant, &afhub_dds_BodyCommand_desc, "afhub/body_command", NULL, NULL),
      "command topic");
  /* The bridge's QoS: infos reliable and transient local; states and commands best
   * effort, keep last 1. */
  dds_qos_t* info_qos = dds_create_qos();
  dds_qset_reliability(info_qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(info_qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(info_qos, DDS_HISTORY_KEEP_LAST, 1);
  dds_qos_t* stream_qos = dds_create_qos();
  dds_qset_reliability(stream_qos, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(stream_qos, DDS_HISTORY_KEEP_LAST, 1);
  const dds_entity_t info_writer =
      must(dds_create_writer(participant, info_topic, info_qos, NULL), "info writer");
  const dds_entity_t state_writer =
      must(dds_create_writer(participant, state_topic, stream_qos, NULL), "state writer");
  const dds_entity_t command_writer =
      must(dds_create_writer(participant, command_topic, stream_qos, NULL), "command writer");
  dds_qos_t* others_qos = dds_create_qos();  // its own states are not counted
  dds_copy_qos(others_qos, stream_qos);
  dds_qset_ignorelocal(others_qos, DDS_IGNORELOCAL_PARTICIPANT);
  const dds_entity_t state_reader =
      must(dds_create_reader(participant, state_topic, others_qos, NULL), "state reader");
  const dds_entity_t command_reader =
      must(dds_create_reader(participant, command_topic, others_qos, NULL), "command reader");

  char(*names)[64] = calloc(joints ? joints : 1, sizeof *names);
  for (unsigned j = 0; j < joints; ++j) snprintf(names[j], sizeof names[j], "j%u", j);
  afhub_dds_BodyInfo info;
  memset(&info, 0, sizeof info);
  info.joint_names._buffer = names;
  info.joint_names._length = info.joint_names._maximum = joints;
  for (unsigned b = 0; b < bodies; ++b) {
    snprintf(info.body, sizeof info.body, "%s%u", prefix, b);
    must(dds_write(info_writer, &info), "writing a body's info");
  }

  afhub_dds_JointSample* samples = calloc(joints ? joints : 1, sizeof *samples);
  afhub_dds_BodyState state;
  memset(&state, 0, sizeof state);
  state.pose.orientation.w = 1.0;
  state.mass_kg = 1.0;
  state.joints._buffer = samples;
  state.joints._length = state.joints._maximum = joints;
  afhub_dds_JointCommand* targets = calloc(command_joints, sizeof *targets);
  afhub_dds_BodyCommand command;
  memset(&command, 0, sizeof command);
  command.pose.orientation.w = 1.0;
  command.joints._buffer = targets;
  command.joints._length = command.joints._maximum = command_joints;
  if (command_body) snprintf(command.body, sizeof command.body, "%s", command_body);

  unsigned long long received = 0, sent = 0, commanded = 0, step = 0;
  const double start = now_s();
  double next_state = start, next_print = start + 1.0;
  afhub_dds_BodyState in;
  memset(&in, 0, sizeof in);
  void* in_samples[1] = {&in};
  dds_sample_info_t in_info;
  afhub_dds_BodyCommand command_in;
  memset(&command_in, 0, sizeof command_in);
  void* command_samples[1] = {&command_in};
  const size_t prefix_length = strlen(prefix);
  while (!stopping && (seconds <= 0.0 || now_s() - start < seconds)) {
    const double now = now_s();
    while (dds_take(state_reader, in_samples, &in_info, 1, 1) > 0)
      if (in_info.valid_data) ++received;
    while (dds_take(command_reader, command_samples, &in_info, 1, 1) > 0)
      if (in_info.valid_data && !strncmp(command_in.body, prefix, prefix_length)) ++commanded;
    if (state_rate > 0.0 && now >= next_state) {
      ++step;
      state.header.sequence_number = step;
      state.header.sim_step = step;
      state.header.sim_time_s = (double)step / state_rate;
      for (unsigned j = 0; j < joints; ++j) samples[j].position = 0.001 * (double)step;
      for (unsigned b = 0; b < bodies; ++b) {
        snprintf(state.body, sizeof state.body, "%s%u", prefix, b);
        dds_write(state_writer, &state);
      }
      next_state += 1.0 / state_rate;
      if (next_state < now) next_state = now;
    }
    if (command_body) {
      for (unsigned j = 0; j < command_joints; ++j) {
        targets[j].value = 0.3;
        targets[j].type = 1; /* a position */
      }
      ++command.header.sequence_number;
      if (dds_write(command_writer, &command) >= 0) ++sent;
    }
    if (now >= next_print) {
      printf("dds_peer: states received %llu, commands sent %llu, commands received %llu\n",
             received, sent, commanded);
      fflush(stdout);
      next_print += 1.0;
    }
    struct timespec pause = {0, 2000000};  // 500 Hz
    nanosleep(&pause, NULL);
  }
  printf("dds_peer: states received %llu, commands sent %llu, commands received %llu\n", received,
         sent, commanded);
  dds_sample_free(&in, &afhub_dds_BodyState_desc, DDS_FREE_CONTENTS);
  dds_sample_free(&command_in, &afhub_dds_BodyCommand_desc, DDS_FREE_CONTENTS);
  dds_delete(participant);
  dds_delete_qos(info_qos);
  dds_delete_qos(stream_qos);
  dds_delete_qos(others_qos);
  free(names);
  free(samples);
  free(targets);
  return 0;
}
