#include "protocols/model_file/urdf.h"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <mutex>
#include <numbers>
#include <set>
#include <sstream>

#include "core/util/atomic_file.h"
#include "core/util/markup_text.h"
#include "protocols/model_file/model_file.h"

namespace selfcal {
namespace {

// urdfdom reports through console_bridge (stderr by default). Library code must not print, and
// the message belongs in our error: collect it while parsing. console_bridge's handler is global,
// hence the lock.
class CollectingHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) {
      if (!messages_.empty()) messages_ += "; ";
      messages_ += text;
    }
  }
  const std::string& messages() const { return messages_; }

 private:
  std::string messages_;
};

std::mutex parse_mutex;

Eigen::Isometry3d ToIsometry(const urdf::Pose& pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Quaterniond q(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() << pose.position.x, pose.position.y, pose.position.z;
  return T;
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

void CollectLeaves(const urdf::LinkConstSharedPtr& link, std::vector<std::string>& leaves) {
  if (link->child_links.empty()) {
    leaves.push_back(link->name);
    return;
  }
  for (const auto& child : link->child_links) CollectLeaves(child, leaves);
}

std::string Number(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

// URDF's rpy: R = rot_z(yaw) rot_y(pitch) rot_x(roll). Yaw is read first and peeled off exactly,
// which keeps the decomposition accurate at pitch = +-90 deg.
Eigen::Vector3d RollPitchYaw(const Eigen::Matrix3d& R) {
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  const Eigen::Matrix3d rest = Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitZ()) * R;
  // rest = rot_y(p) rot_x(r) = [[cp, sp sr, sp cr], [0, cr, -sr], [-sp, cp sr, cp cr]]
  const double pitch = std::atan2(-rest(2, 0), rest(0, 0));
  const double roll = std::atan2(-rest(1, 2), rest(1, 1));
  return {roll, pitch, yaw};
}

std::string Origin(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d rpy = RollPitchYaw(T.linear());
  const Eigen::Vector3d& t = T.translation();
  return "<origin xyz=\"" + Number(t.x()) + " " + Number(t.y()) + " " + Number(t.z()) +
         "\" rpy=\"" + Number(rpy.x()) + " " + Number(rpy.y()) + " " + Number(rpy.z()) + "\"/>";
}

// urdfdom's parse, with its console messages collected into the error.
Expected<urdf::ModelInterfaceSharedPtr> ParseUrdfModel(const std::string& xml,
                                                       const std::string& name) {
  urdf::ModelInterfaceSharedPtr urdf_model;
  std::string messages;
  {
    const std::lock_guard lock(parse_mutex);
    CollectingHandler handler;
    console_bridge::useOutputHandler(&handler);
    try {
      urdf_model = urdf::parseURDF(xml);
    } catch (const std::exception& e) {
      handler.log(e.what(), console_bridge::CONSOLE_BRIDGE_LOG_ERROR, "", 0);
    }
    console_bridge::restorePreviousOutputHandler();
    messages = handler.messages();
  }
  if (!urdf_model) {
    return Error{name + ": not a valid URDF" + (messages.empty() ? "" : ": " + messages)};
  }
  return urdf_model;
}

// The tip link: the one named, or the only leaf below the base.
Expected<urdf::LinkConstSharedPtr> FindTip(const urdf::ModelInterface& urdf_model,
                                           const urdf::LinkConstSharedPtr& base,
                                           const std::string& tip_link, const std::string& name) {
  if (!tip_link.empty()) {
    urdf::LinkConstSharedPtr tip = urdf_model.getLink(tip_link);
    if (!tip) return Error{name + ": no link named '" + tip_link + "'"};
    return tip;
  }
  std::vector<std::string> leaves;
  CollectLeaves(base, leaves);
  if (leaves.size() != 1) {
    return Error{name + ": several tip links below '" + base->name + "' (" + JoinNames(leaves) +
                 "): choose one"};
  }
  return urdf_model.getLink(leaves.front());
}

// The joints from the base to the tip, in that order.
Expected<std::vector<urdf::JointConstSharedPtr>> JointPath(const urdf::ModelInterface& urdf_model,
                                                           const urdf::LinkConstSharedPtr& base,
                                                           const urdf::LinkConstSharedPtr& tip,
                                                           const std::string& name) {
  std::vector<urdf::JointConstSharedPtr> path;
  for (urdf::LinkConstSharedPtr link = tip; link != base;) {
    if (!link->parent_joint) {
      return Error{name + ": link '" + tip->name + "' is not below link '" + base->name + "'"};
    }
    path.push_back(link->parent_joint);
    link = urdf_model.getLink(link->parent_joint->parent_link_name);
    if (!link) return Error{name + ": broken link tree at '" + path.back()->name + "'"};
  }
  std::reverse(path.begin(), path.end());
  return path;
}

// A movable URDF joint as a chain joint (its origin is composed by the caller). Sets
// `defaulted_velocity` when the URDF gives no usable velocity limit.
Expected<ChainJoint> ToChainJoint(const urdf::Joint& joint, const std::string& where,
                                  const UrdfImportOptions& options,
                                  const std::function<void(const std::string&)>& note,
                                  bool& defaulted_velocity) {
  if (joint.type != urdf::Joint::REVOLUTE && joint.type != urdf::Joint::CONTINUOUS &&
      joint.type != urdf::Joint::PRISMATIC) {
    return Error{where + ": only revolute, continuous, prismatic and fixed joints are supported"};
  }
  if (joint.mimic) return Error{where + ": mimic joints are not supported"};
  ChainJoint chain_joint;
  chain_joint.spec.name = joint.name;
  chain_joint.spec.type =
      joint.type == urdf::Joint::PRISMATIC ? JointType::kPrismatic : JointType::kRevolute;
  chain_joint.axis = Eigen::Vector3d(joint.axis.x, joint.axis.y, joint.axis.z);
  if (!chain_joint.axis.allFinite() || chain_joint.axis.norm() < 1e-12) {
    return Error{where + ": axis is zero or not finite"};
  }
  if (joint.type == urdf::Joint::CONTINUOUS) {
    chain_joint.spec.lower = -std::numbers::pi;
    chain_joint.spec.upper = std::numbers::pi;
    note("joint " + joint.name + " is continuous: limits set to [-pi, pi]");
  } else {
    if (!joint.limits) return Error{where + ": has no <limit>"};
    chain_joint.spec.lower = joint.limits->lower;
    chain_joint.spec.upper = joint.limits->upper;
    if (!(chain_joint.spec.lower < chain_joint.spec.upper)) {
      return Error{where + ": lower limit is not below the upper limit"};
    }
  }
  chain_joint.spec.max_velocity = options.default_max_velocity;
  if (joint.limits && joint.limits->velocity > 0 && std::isfinite(joint.limits->velocity)) {
    chain_joint.spec.max_velocity = joint.limits->velocity;
  } else {
    defaulted_velocity = true;
  }
  chain_joint.spec.max_acceleration = options.default_max_acceleration;
  return chain_joint;
}

}  // namespace

Expected<GenericChain> ParseUrdfChain(const std::string& xml, const std::string& name,
                                      const UrdfImportOptions& options,
                                      std::vector<std::string>* notes) {
  auto urdf_model = ParseUrdfModel(xml, name);
  if (!urdf_model) return urdf_model.error();
  const std::function<void(const std::string&)> note = [&](const std::string& text) {
    if (notes != nullptr) notes->push_back(text);
  };

  urdf::LinkConstSharedPtr base = (*urdf_model)->getRoot();
  if (!options.base_link.empty()) base = (*urdf_model)->getLink(options.base_link);
  if (!base) return Error{name + ": no link named '" + options.base_link + "'"};
  auto tip = FindTip(**urdf_model, base, options.tip_link, name);
  if (!tip) return tip.error();
  auto path = JointPath(**urdf_model, base, *tip, name);
  if (!path) return path.error();

  GenericChain chain;
  chain.name = (*urdf_model)->getName();
  Eigen::Isometry3d pending = Eigen::Isometry3d::Identity();
  bool defaulted_velocity = false;
  for (const auto& joint : *path) {
    const std::string where = name + ": joint '" + joint->name + "'";
    const Eigen::Isometry3d origin = ToIsometry(joint->parent_to_joint_origin_transform);
    if (!origin.matrix().allFinite()) return Error{where + ": origin is not finite"};
    if (joint->type == urdf::Joint::FIXED) {
      pending = pending * origin;
      continue;
    }
    auto chain_joint = ToChainJoint(*joint, where, options, note, defaulted_velocity);
    if (!chain_joint) return chain_joint.error();
    chain.fixed.push_back(pending * origin);
    chain.joints.push_back(*chain_joint);
    pending = Eigen::Isometry3d::Identity();
  }
  chain.fixed.push_back(pending);
  if (chain.joints.empty()) {
    return Error{name + ": no movable joint between '" + base->name + "' and '" + (*tip)->name +
                 "'"};
  }
  note("chain " + base->name + " -> " + (*tip)->name + ": " + std::to_string(chain.joints.size()) +
       " joints; accelerations set to " + Number(options.default_max_acceleration) +
       " (URDF has none)");
  if (defaulted_velocity) {
    note("joints without a velocity limit got " + Number(options.default_max_velocity));
  }
  return chain;
}

Expected<McpcConversion> ImportUrdf(const std::string& xml, const std::string& name,
                                    const UrdfImportOptions& options) {
  std::vector<std::string> notes;
  auto chain = ParseUrdfChain(xml, name, options, &notes);
  if (!chain) return chain.error();
  auto converted = ChainToMcpc(*chain);
  if (!converted) return Error{name + ": " + converted.error().message};
  notes.insert(notes.end(), converted->notes.begin(), converted->notes.end());
  converted->notes = std::move(notes);
  return converted;
}

Expected<McpcConversion> ReadUrdfFile(const std::string& path, const UrdfImportOptions& options) {
  auto text = ReadFile(path);
  if (!text) return text.error();
  return ImportUrdf(*text, path, options);
}

std::string FormatUrdf(const RobotModel& model) {
  const GenericChain chain = McpcToChain(model);
  // Unique link names even if a joint is called "base" or "tool".
  std::set<std::string> used;
  auto unique = [&](std::string candidate) {
    const std::string stem = candidate;
    for (int suffix = 2; used.count(candidate) > 0; ++suffix) {
      candidate = stem + "_" + std::to_string(suffix);
    }
    used.insert(candidate);
    return candidate;
  };
  std::vector<std::string> links = {unique("base_link")};
  for (const auto& joint : model.joints) links.push_back(unique(joint.name + "_link"));
  links.push_back(unique("tool_link"));
  std::set<std::string> joint_names;
  for (const auto& joint : model.joints) joint_names.insert(joint.name);
  std::string tool_joint = "tool_joint";
  for (int suffix = 2; joint_names.count(tool_joint) > 0; ++suffix) {
    tool_joint = "tool_joint_" + std::to_string(suffix);
  }

  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n"
      << "<!-- Written by selfcal from the MCPC model '" << MarkupText(model.name) << "'.\n"
      << "     Joint i turns (or slides) about its own z axis; its origin is the MCPC transform\n"
      << "     st(s_{i-1}) (st(s_0) for the first joint) and tool_joint carries st(s_n).\n"
      << "     Effort limits are unknown (0); acceleration limits are not part of URDF. -->\n"
      << "<robot name=\"" << MarkupText(model.name) << "\">\n";
  for (const auto& link : links) out << "  <link name=\"" << MarkupText(link) << "\"/>\n";
  for (std::size_t i = 0; i < model.JointCount(); ++i) {
    const JointSpec& joint = model.joints[i];
    out << "  <joint name=\"" << MarkupText(joint.name) << "\" type=\""
        << kJointTypeNames.Name(joint.type) << "\">\n"
        << "    <parent link=\"" << MarkupText(links[i]) << "\"/>\n"
        << "    <child link=\"" << MarkupText(links[i + 1]) << "\"/>\n"
        << "    " << Origin(chain.fixed[i]) << "\n"
        << "    <axis xyz=\"0 0 1\"/>\n"
        << "    <limit lower=\"" << Number(joint.lower) << "\" upper=\"" << Number(joint.upper)
        << "\" effort=\"0\" velocity=\"" << Number(joint.max_velocity) << "\"/>\n"
        << "  </joint>\n";
  }
  out << "  <joint name=\"" << MarkupText(tool_joint) << "\" type=\"fixed\">\n"
      << "    <parent link=\"" << MarkupText(links[model.JointCount()]) << "\"/>\n"
      << "    <child link=\"" << MarkupText(links.back()) << "\"/>\n"
      << "    " << Origin(chain.fixed.back()) << "\n"
      << "  </joint>\n"
      << "</robot>\n";
  return out.str();
}

Status WriteUrdfFile(const std::string& path, const RobotModel& model) {
  return WriteFileAtomically(path, FormatUrdf(model));
}

}  // namespace selfcal
