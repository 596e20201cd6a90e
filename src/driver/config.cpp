// Scene files: strict XML reading, then every section parsed and checked from its declaration.
#include <sinew/core/parameters.hpp>
#include <sinew/core/xml_input.hpp>
#include <sinew/driver/config.hpp>

#include <sinew/discretization/mesh_file.hpp>
#include <sinew/discretization/rig_file.hpp>
#include <sinew/discretization/triangle_surface.hpp>
#include <sinew/scenes/scene.hpp>

#include <Tpetra_Core.hpp>

#include <algorithm>
#include <filesystem>
#include <sstream>

namespace sinew {

SceneConfig make_scene(const Teuchos::RCP<Teuchos::ParameterList>& params, const std::string& name) {
  SceneConfig c;
  c.file = name;
  try {
    c.params = parse_section<SceneFileParameters>(*params, "the top-level list");
    if (c.params.time.dynamic() && params->isSublist("Loading") && params->sublist("Loading").isParameter("Steps"))
      throw InputError("Loading: 'Steps' does not apply to a dynamic run (Time/Frames and Substeps set the time steps)");
    // The skin's caches need a skin: the surface a voxelized or rigged body was filled from.
    if (!has_skin(c.params.mesh.type))
      for (const auto& [entry, on] : {std::make_pair("Skin glTF", c.params.output.skin_gltf),
                                      std::make_pair("Skin PC2", c.params.output.skin_pc2)})
        if (on.value_or(false))
          throw InputError(std::string("Output: '") + entry + "' needs a skin, which only Mesh/Type voxelize or rig has (this "
                           "scene's mesh is '" + to_string(c.params.mesh.type) + "'; its boundary surface is in surface_NNNNNN.obj)");
    // A rig's rest pose is one for the skin and the bones: the Skeleton says it, the Mesh follows.
    if (c.params.skeleton.rest_time >= 0.0) {
      if (c.params.mesh.type != MeshType::Rig || c.params.mesh.rig != c.params.skeleton.rig)
        throw InputError("Skeleton: 'Rest time' needs Mesh/Type rig with the same 'Rig' file (the skin is voxelized in that pose)");
      // (Retargeting: the skeleton's clip is the other file's; the rest is a frame of the rig's first.)
      c.params.mesh.rig_rest_clip = c.params.skeleton.retarget.empty() ? c.params.skeleton.clip : "";
      c.params.mesh.rig_rest_time = c.params.skeleton.rest_time;
    }
    // 'Bone attachment' auto: soft bones where the barrier holds self contact, whose collision test bounds
    // the free nodes' steps only (a prescribed bone node would carry the surface through a face: with
    // fixed bones BCN_Epileptic's clip fails at its knee, docs/performance.md), fixed bones otherwise.
    SkeletonParameters& sk = c.params.skeleton;
    if (sk.attachment == SkeletonParameters::Attachment::Auto) {
      const ContactParameters& contact = c.params.terms.of<Contact>();
      const bool barrier = contact.self && contact.model == ContactParameters::Model::Barrier;
      sk.attachment = barrier ? SkeletonParameters::Attachment::Soft : SkeletonParameters::Attachment::Fixed;
      if (!barrier && sk.bone_stiffness > 0.0)
        throw InputError("Skeleton: 'Bone stiffness' applies to soft bones: 'Bone attachment' soft, or auto (the default) "
                         "with Contact/'Self contact model' barrier and 'Self contact' on; these bones are fixed");
    }
  } catch (const InputError& e) {
    throw e.prefixed(name + ": ");
  }
  return c;
}

SceneConfig read_scene(const std::string& path) {
  SceneConfig c = make_scene(read_parameter_file(path), path);
  // Files named in a scene are found next to it, wherever sinew runs.
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  auto resolve = [&](std::string& f) {
    if (!f.empty() && std::filesystem::path(f).is_relative()) f = (folder / f).lexically_normal().string();
  };
  resolve(c.params.mesh.file);
  resolve(c.params.mesh.surface);
  resolve(c.params.skeleton.motion_file);
  resolve(c.params.mesh.rig);
  resolve(c.params.skeleton.rig);
  resolve(c.params.skeleton.retarget);
  for (auto& [name, bc] : c.params.loading.conditions) resolve(bc.region.surface);
  for (auto& [name, bone] : c.params.skeleton.bones) resolve(bone.region.surface);
  c.params.terms.resolve_paths(resolve);
  return c;
}

void check_mesh_file(const SceneConfig& c) {
  const SceneFileParameters& p = c.params;
  try {
    // Closed surfaces (a voxelized body, 'inside' regions) are small: read and check them whole.
    if (p.mesh.type == MeshType::Voxelize) read_triangle_surface(p.mesh.surface);
    // A rig: the file, the meshes named as the flesh, the clip named for the bones.
    if (p.mesh.type == MeshType::Rig) {
      RigFile rig;
      try {
        rig = read_rig_file(p.mesh.rig);
      } catch (const InputError& e) {
        throw e.prefixed("Mesh: ");
      }
      // The rest pose within its clip (Skeleton's 'Rest time', which the mesh takes).
      if (p.mesh.rig_rest_time >= 0.0)
        if (const RigClip* clip = rig.clip(p.mesh.rig_rest_clip)) check_rest_time(*clip, p.mesh.rig_rest_time, p.mesh.rig);
      try {
        rig_surface(rig, p.mesh.rig_meshes, p.mesh.rig_rest_time >= 0.0 ? rig.clip(p.mesh.rig_rest_clip) : nullptr, p.mesh.rig_rest_time);
      } catch (const InputError& e) {
        throw e.prefixed("Mesh: ");
      }
    }
    if (!p.skeleton.rig.empty()) {
      const RigFile rig = read_rig_file(p.skeleton.rig);
      RigFile source;  // a retargeted motion's file
      if (!p.skeleton.retarget.empty()) source = read_rig_file(p.skeleton.retarget);
      const RigFile& moving = p.skeleton.retarget.empty() ? rig : source;
      if (!moving.clip(p.skeleton.clip))
        throw InputError("Skeleton: " + moving.path + " has no clip" + (p.skeleton.clip.empty() ? "" : " '" + p.skeleton.clip + "'"));
      if (!p.skeleton.retarget.empty()) {
        try {
          const Retarget check(rig, rig.pose(nullptr, 0.0), moving, *moving.clip(p.skeleton.clip), 0.0,
                               Retarget::parse_map(p.skeleton.joint_map), p.skeleton.retarget_scale);
        } catch (const InputError& e) {
          throw e.prefixed("Skeleton: ");
        }
      }
    }
    auto surface = [](const RegionParameters& r, const std::string& where) {
      if (r.region != "inside") return;
      try {
        read_triangle_surface(r.surface);
      } catch (const InputError& e) {
        throw e.prefixed(where + ": ");
      }
    };
    for (const auto& [name, bc] : p.loading.conditions) surface(bc.region, "Loading/Boundary conditions/" + name);
    for (const auto& [name, bone] : p.skeleton.bones) surface(bone.region, "Skeleton/Bones/" + name);
    for (const auto& [name, collider] : p.terms.of<Contact>().colliders) {
      if (collider.shape != ColliderParameters::Shape::Mesh) continue;
      try {
        read_triangle_surface(collider.surface);
      } catch (const InputError& e) {
        throw e.prefixed("Contact/Colliders/" + name + ": ");
      }
    }
    // A collider attached to a bone needs that bone.
    for (const auto& [name, collider] : p.terms.of<Contact>().colliders)
      if (!collider.bone.empty() && p.skeleton.rig.empty() && std::none_of(p.skeleton.bones.begin(), p.skeleton.bones.end(),
                                                 [&](const auto& b) { return b.first == collider.bone; }))
        throw InputError("Contact/Colliders/" + name + ": 'Bone' \"" + collider.bone + "\" is not a bone of the Skeleton");
  } catch (const InputError& e) {
    throw e.prefixed(c.file + ": ");
  }
  if (p.mesh.type != MeshType::File) return;
  try {
    const MeshGroups g = read_mesh_groups(p.mesh.file);
    for (const auto& [region, law] : p.material.regions)
      if (std::find(g.element_groups.begin(), g.element_groups.end(), region) == g.element_groups.end())
        throw unknown_group("Material/" + region, region, {}, g.element_groups);
    auto check_group = [&](const RegionParameters& r, const std::string& where) {
      for (const auto& name : r.groups())
        if (std::find(g.node_groups.begin(), g.node_groups.end(), name) == g.node_groups.end() &&
            std::find(g.element_groups.begin(), g.element_groups.end(), name) == g.element_groups.end())
          throw unknown_group(where, name, g.node_groups, g.element_groups);
    };
    for (const auto& [name, bc] : p.loading.conditions) check_group(bc.region, "Loading/Boundary conditions/" + name);
    for (const auto& [name, bone] : p.skeleton.bones) check_group(bone.region, "Skeleton/Bones/" + name);
  } catch (const InputError& e) {
    throw e.prefixed(c.file + ": ");
  }
}

std::string parameter_reference() {
  std::ostringstream os;
  os << "Every entry of a Sinew scene file: name (type, default) and meaning, [allowed range].\n\n";
  print_section<SceneFileParameters>(os, "Scene file");
  return os.str();
}

std::string describe(const SceneConfig& c) {
  // (A rig's files are read again here: check_mesh_file has read them once without error.)
  auto indented = [](const std::string& text) {
    std::string out;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) out += "  " + line + "\n";
    return out;
  };
  const SceneFileParameters& p = c.params;
  std::ostringstream os;
  os.precision(6);
  os << "scene: " << p.scene << " (" << c.file << ")\n";
  if (!p.description.empty()) os << "  " << p.description << "\n";
  if (p.mesh.type == MeshType::File)
    os << "mesh: file " << p.mesh.file << "\n";
  else if (p.mesh.type == MeshType::Voxelize)
    os << "mesh: hex8 cells of size " << p.mesh.cell_size << " filling " << p.mesh.surface << "\n";
  else if (p.mesh.type == MeshType::Rig)  // with what the file holds (meshes, joints, clips), to choose from
    os << "mesh: hex8 cells of size " << p.mesh.cell_size << " filling the skin of " << p.mesh.rig << "\n"
       << indented(describe(read_rig_file(p.mesh.rig)));
  else
    os << "mesh: " << to_string(p.mesh.type) << ", " << to_string(p.mesh.element) << ", " << p.mesh.cells[0] << " x " << p.mesh.cells[1]
       << " x " << p.mesh.cells[2] << " cells\n";
  os << "material: " << describe(p.material.law.spec()) << "\n";
  for (const auto& [region, law] : p.material.regions) os << "  region " << region << ": " << describe(law.spec()) << "\n";
  if (p.time.dynamic()) {
    static const char* names[] = {"quasi-static", "backward Euler", "implicit midpoint"};
    os << "time: " << names[static_cast<int>(p.time.integrator)] << ", " << p.time.frames << " frames at "
       << p.time.frame_rate << " per second, " << p.time.substeps << " substep" << (p.time.substeps > 1 ? "s" : "")
       << " per frame (h = " << 1.0 / (p.time.frame_rate * p.time.substeps) << " s), " << (p.time.lumped ? "lumped" : "consistent")
       << " mass\n";
  }
  os << "loading: " << (p.time.dynamic() ? p.time.steps() : p.loading.steps) << " step"
     << ((p.time.dynamic() ? p.time.steps() : p.loading.steps) > 1 ? "s" : "") << ", "
     << p.loading.conditions.size() << " boundary condition" << (p.loading.conditions.size() == 1 ? "" : "s") << "\n";
  for (const auto& [name, bc] : p.loading.conditions)
    os << "  " << name << ": " << bc.region.region << ", components " << bc.components << "\n";
  if (!p.skeleton.rig.empty()) {
    os << "skeleton: the joints of " << p.skeleton.rig << ", clip " << (p.skeleton.clip.empty() ? "(the first)" : "'" + p.skeleton.clip + "'")
       << " of " << (p.skeleton.retarget.empty() ? p.skeleton.rig : p.skeleton.retarget) << " from " << p.skeleton.clip_start << " s to ";
    if (p.skeleton.clip_end >= 0.0)
      os << p.skeleton.clip_end << " s";
    else
      os << "its end";
    if (p.skeleton.rest_time >= 0.0) os << ", rest pose at " << p.skeleton.rest_time << " s of its own clip";
    os << ", " << p.skeleton.attachment_word() << " bones\n";
    if (p.mesh.rig != p.skeleton.rig) os << indented(describe(read_rig_file(p.skeleton.rig)));
    if (!p.skeleton.retarget.empty()) {
      os << "  the clip retargeted from " << p.skeleton.retarget << " by " << Retarget::parse_map(p.skeleton.joint_map).size()
         << " joint pairs:\n";
      os << indented(indented(describe(read_rig_file(p.skeleton.retarget))));
    }
  }
  if (!p.skeleton.bones.empty()) {
    os << "skeleton: " << p.skeleton.bones.size() << " " << p.skeleton.attachment_word() << " bones"
       << (p.skeleton.skinning ? ", skinning guess" : "") << "\n";
    for (const auto& [name, b] : p.skeleton.bones)
      os << "  " << name << ": " << b.region.region << (b.parent.empty() ? "" : ", child of " + b.parent) << ", "
         << b.keyframes.size() << " keyframes\n";
  }
  const ContactParameters& contact = p.terms.of<Contact>();
  if (contact.active()) {
    os << "contact: self contact " << (contact.self ? "on" : "off") << ", " << contact.colliders.size() << " collider"
       << (contact.colliders.size() == 1 ? "" : "s") << "\n";
    for (const auto& [name, c] : contact.colliders) {
      static const char* shapes[] = {"half-space", "sphere", "capsule", "cylinder", "mesh"};
      os << "  " << name << ": " << shapes[static_cast<int>(c.shape)]
         << (c.bone.empty() ? (c.keyframes.empty() ? ", fixed" : ", " + std::to_string(c.keyframes.size()) + " keyframes")
                            : ", on bone " + c.bone)
         << "\n";
    }
  }
  os << "solver: |F| < " << (p.solver.absolute_tolerance > 0.0 ? std::to_string(p.solver.absolute_tolerance) : "max(1e-2, 1e-6 (mu_L + lambda_L) h^2)")
     << ", at most " << p.solver.max_iterations
     << " Newton iterations, line search " << nox_name(p.solver.line_search) << " on the "
     << (p.solver.merit == SolverParameters::Merit::Energy ? "energy" : "residual") << ", CG with "
     << stratimikos_name(p.solver.preconditioner) << "\n";
  os << "output: " << (p.output.directory.empty() ? "results/" + p.scene : p.output.directory) << "\n";
  return os.str();
}

std::string describe_joints(const SceneConfig& c) {
  if (c.params.skeleton.rig.empty()) return "";
  auto comm = Tpetra::getDefaultComm();
  const SceneDescription d = c.scene();
  try {
    const Mesh mesh = build_scene_mesh(d.mesh, *comm);
    const Skeleton skeleton(d.skeleton, mesh, *comm, "Skeleton");
    return skeleton.joint_listing();
  } catch (const InputError& e) {
    throw e.prefixed(c.file + ": ");
  }
}

}  // namespace sinew
