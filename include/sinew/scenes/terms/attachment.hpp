// Attachments in a scene: bodies that are separate pieces of one mesh (a Gmsh file whose volumes do not
// share nodes: a muscle inside fat, a skin layer over flesh, a block on a block) held together where
// they touch at rest, fixed (the surfaces move together) or sliding (the normal gap stays closed, the
// tangential motion is free). The energy and its rounds: algebra/terms/attachment.hpp.
//
//   <ParameterList name="Attachments">
//     <ParameterList name="muscle in fat">
//       <Parameter name="Type" type="string" value="sliding"/>
//       <Parameter name="Region" type="string" value="group biceps"/>
//       <Parameter name="Target" type="string" value="group fat"/>
//       <Parameter name="Distance" type="double" value="1.0e-3"/>
//     </ParameterList>
//   </ParameterList>
//
// The samples are the boundary nodes of 'Region' (any region: a group, a box, a face...); the target is
// the boundary faces whose nodes all lie in 'Target' (all, 'group NAME[, NAME]' or a face of the
// bounding box). List fixed attachments before sliding ones where they meet: a sample belongs to the
// first attachment that reaches it. The term is this file, algebra/terms/attachment.hpp with
// src/algebra/attachment.cpp, and a line in term_registry.hpp.
#pragma once

#include <sinew/algebra/terms/attachment.hpp>
#include <sinew/core/collective.hpp>
#include <sinew/core/errors.hpp>
#include <sinew/scenes/region.hpp>
#include <sinew/scenes/term_kind.hpp>

#include <algorithm>
#include <memory>

namespace sinew {

inline const Choices<AttachmentKind>& attachment_kind_choices() {
  static const Choices<AttachmentKind> c = {{"fixed", AttachmentKind::Fixed}, {"sliding", AttachmentKind::Sliding}};
  return c;
}

struct AttachmentParameters {
  AttachmentKind type = AttachmentKind::Fixed;
  RegionParameters region;
  std::string target;
  double distance = 0.0, stiffness = 0.0, tolerance = 0.0;
  int rounds = 10;

  template <class V>
  void visit(V& v) {
    v.choice("Type", type, AttachmentKind::Fixed, attachment_kind_choices(),
             "fixed (the two surfaces move together) or sliding (the normal gap stays closed, tangential motion is free)");
    v.inline_section(region);
    v.entry("Target", target, std::string(""),
            "the surface the region's boundary nodes attach to (required): all, 'group NAME[, NAME]' or 'face x-' ... "
            "'face z+'; its boundary faces with all nodes in it");
    v.entry("Distance", distance, 0.0,
            "the region's boundary nodes within this distance of the target at rest are attached (required; an "
            "attachment that reaches no node is an error)",
            Range::non_negative());
    v.entry("Stiffness", stiffness, 0.0,
            "penalty k: traction per unit of gap (0: 10 (mu_L + lambda_L) / h, as contact's, h the mean edge length)",
            Range::non_negative());
    v.entry("Tolerance", tolerance, 0.0,
            "the gap each step closes to: the tractions are raised between solves until no gap exceeds it (0: h / 100)",
            Range::non_negative());
    v.entry("Maximum rounds", rounds, 10, "solves per step at most while a gap exceeds the tolerance", Range::closed(1, 100));
  }
  template <class Context>
  void check(const Context& c) const {
    if (target.empty()) c.fail("missing entry 'Target' (the surface to attach to)", InputErrorKind::MissingEntry);
    const bool face = target.rfind("face ", 0) == 0 && target.size() == 7 && target[5] >= 'x' && target[5] <= 'z' &&
                      (target[6] == '-' || target[6] == '+');
    if (!target.empty() && target != "all" && target.rfind("group ", 0) != 0 && !face)
      c.fail("'Target' must be all, 'group NAME[, NAME]' or 'face x-' ... 'face z+', got \"" + target + "\"");
    if (!(distance > 0.0)) c.fail("missing entry 'Distance' (> 0): how far from the target at rest a node may be attached",
                                  InputErrorKind::MissingEntry);
  }
};

struct AttachmentsParameters {
  NamedSections<AttachmentParameters> attachments;

  template <class V>
  void visit(V& v) {
    v.other_sublists(attachments, "one sublist per attachment, named as you like (Type, Region, Target, Distance)");
  }
};

struct Attachments {
  using Parameters = AttachmentsParameters;
  static constexpr const char* section = "Attachments";
  static constexpr const char* doc =
      "attachments between bodies (separate pieces of the mesh): fixed or sliding, found by proximity at rest";
  static bool active(const Parameters& p) { return !p.attachments.empty(); }
  static void resolve_paths(Parameters& p, const std::function<void(std::string&)>& resolve) {
    for (auto& [name, a] : p.attachments) resolve(a.region.surface);
  }

  // Collective. Throws InputError naming the attachment whose regions are not the mesh's, hold no
  // surface, or lie farther apart than its distance.
  static std::shared_ptr<EnergyTerm> make(const Parameters& p, const TermContext& c) {
    System& sys = c.system;
    const Mesh& mesh = sys.mesh();
    const MPI_Comm comm = raw_comm(c.comm);
    auto global_nodes = [&](const RegionParameters& r, const std::string& where) {
      std::vector<GlobalId> mine;
      for (int n : select_region(mesh, c.comm, r, where))
        if (static_cast<std::size_t>(n) < mesh.n_owned_nodes) mine.push_back(mesh.node_gid[n]);
      std::vector<GlobalId> all = allgatherv(comm, mine);
      std::sort(all.begin(), all.end());
      return all;
    };
    const double h = sys.cell_size();
    std::vector<AttachmentSpec> specs;
    int rounds = 1;
    for (const auto& [name, a] : p.attachments) {
      const std::string where = "Attachments/" + name;
      AttachmentSpec s;
      s.name = name;
      s.kind = a.type;
      s.sources = global_nodes(a.region, where);
      RegionParameters target;
      target.region = a.target;
      s.targets = global_nodes(target, where + " 'Target'");
      s.distance = a.distance;
      s.stiffness = a.stiffness > 0.0 ? a.stiffness : 10.0 * sys.stiffness_scale() / h;
      s.tolerance = a.tolerance > 0.0 ? a.tolerance : 1e-2 * h;
      rounds = std::max(rounds, a.rounds);
      specs.push_back(std::move(s));
    }
    return std::make_shared<AttachmentTerm>(sys, std::move(specs), rounds);
  }
};

}  // namespace sinew
