// Copies of a model get distinct channels (see loaded_copies.hpp). Only channels of
// earlier files count as taken: two bodies of one file on one channel stay an error
// (model_checks.cpp), since within a file it is a mistake, not a copy.
#include "loaded_copies.hpp"

#include "afhub/shm_layout/channel_names.hpp"

namespace afhub::physics::adf {

std::string LoadedChannels::free_name(const std::string& channel,
                                      const std::unordered_map<std::string, SourceLocation>& taken,
                                      const std::unordered_set<std::string>& own) {
  if (!taken.count(channel)) return channel;
  // Ends: at most taken.size() + own.size() names are not free.
  for (std::size_t index = 1;; ++index) {
    const std::string candidate = channel + std::to_string(index);
    if (!taken.count(candidate) && !own.count(candidate)) return candidate;
  }
}

void LoadedChannels::load_as_copies(const FileSpan& span, Model& model,
                                    std::vector<PendingJoint>& joints,
                                    std::vector<std::string>& copy_suffix) {
  std::vector<JointSpec*> file_joints;
  for (std::size_t j = span.first_joint; j < joints.size(); ++j)
    file_joints.push_back(&joints[j].spec);
  for (std::size_t j = span.first_model_joint; j < model.joints.size(); ++j)
    file_joints.push_back(&model.joints[j]);
  std::unordered_set<std::string> own_bodies, own_joints;
  for (std::size_t b = span.first_body; b < model.bodies.size(); ++b)
    own_bodies.insert(model.bodies[b].channel);
  for (std::size_t s = span.first_soft_body; s < model.soft_bodies.size(); ++s)
    own_bodies.insert(model.soft_bodies[s].channel);
  for (const JointSpec* joint : file_joints) own_joints.insert(joint->channel);

  std::size_t renamed = 0;
  std::string first_example;
  // Appends the free index to `name` and `channel`; returns it ("" when kept).
  auto rename = [&](std::string& name, std::string& channel, const SourceLocation& where,
                    const std::unordered_map<std::string, SourceLocation>& taken,
                    const std::unordered_set<std::string>& own) {
    const std::string free = free_name(channel, taken, own);
    if (free == channel) return std::string();
    const std::string suffix = free.substr(channel.size());
    if (auto problem = channel_name_problem(free); !problem.empty())
      fail(where, "loaded as a copy of the body at " + taken.at(channel).str() +
                      ", its channel would be '" + free + "': " + problem);
    if (renamed++ == 0)
      first_example =
          "'" + channel + "' (first at " + taken.at(channel).str() + ") is '" + free + "' here";
    name += suffix;
    channel = free;
    return suffix;
  };
  copy_suffix.resize(model.bodies.size());
  for (std::size_t b = span.first_body; b < model.bodies.size(); ++b) {
    BodySpec& body = model.bodies[b];
    copy_suffix[b] = rename(body.name, body.channel, body.where, bodies_, own_bodies);
  }
  for (std::size_t s = span.first_soft_body; s < model.soft_bodies.size(); ++s) {
    SoftBodySpec& soft = model.soft_bodies[s];
    rename(soft.name, soft.channel, soft.where, bodies_, own_bodies);
  }
  for (JointSpec* joint : file_joints) {
    std::string kept_name = joint->name;  // a joint's name is its body's business
    rename(kept_name, joint->channel, joint->where, joints_, own_joints);
  }
  if (renamed > 0)
    model.warnings.push_back(span.path + ":1:1: warning: " + std::to_string(renamed) +
                             " channel(s) of this file are already used by files loaded before "
                             "it, so it loads as a copy, named as AMBF names copies: " +
                             first_example + "; `afhub ls` shows every name");

  for (std::size_t b = span.first_body; b < model.bodies.size(); ++b)
    bodies_.try_emplace(model.bodies[b].channel, model.bodies[b].where);
  for (std::size_t s = span.first_soft_body; s < model.soft_bodies.size(); ++s)
    bodies_.try_emplace(model.soft_bodies[s].channel, model.soft_bodies[s].where);
  for (const JointSpec* joint : file_joints) joints_.try_emplace(joint->channel, joint->where);
}

}  // namespace afhub::physics::adf
