// Colliders of a scene: shapes and their motions (scenes/contact.hpp).
#include <sinew/algebra/system.hpp>
#include <sinew/core/collective.hpp>
#include <sinew/core/parameters.hpp>
#include <sinew/scenes/contact.hpp>

#include <memory>

namespace sinew {

Colliders::Colliders(const ContactParameters& p, const Skeleton& skeleton, const Teuchos::Comm<int>& comm,
                     const std::string& where)
    : skeleton_(skeleton) {
  using Shape = ColliderParameters::Shape;
  for (const auto& [name, c] : p.colliders) {
    const std::string at = where + "/Colliders/" + name + ": ";
    ColliderShape s;
    switch (c.shape) {
      case Shape::HalfSpace: s.kind = ColliderShape::Kind::HalfSpace; break;
      case Shape::Sphere: s.kind = ColliderShape::Kind::Sphere; break;
      case Shape::Capsule: s.kind = ColliderShape::Kind::Capsule; break;
      case Shape::Cylinder: s.kind = ColliderShape::Kind::Cylinder; break;
      case Shape::Mesh: s.kind = ColliderShape::Kind::Mesh; break;
    }
    s.point = c.point;
    s.normal = c.normal;
    s.center = c.center;
    s.a = c.start;
    s.b = c.end;
    s.radius = c.radius;
    // Every rank reads the surface (it is small) and they agree on failure, so none waits alone.
    collectively(raw_comm(comm), [&] {
      try {
        if (c.shape == Shape::Mesh) s.surface = std::make_shared<TriangleSurface>(read_triangle_surface(c.surface));
        s.prepare();
      } catch (const InputError& e) {
        throw e.prefixed(at);
      }
    });
    int bone = -1;
    if (!c.bone.empty()) {
      for (std::size_t b = 0; b < skeleton.size(); ++b)
        if (skeleton.name(b) == c.bone) bone = static_cast<int>(b);
      if (bone < 0) throw InputError(at + "'Bone' \"" + c.bone + "\" is not a bone of the Skeleton");
    }
    shapes_.push_back(std::move(s));
    tracks_.emplace_back(c.pivot, c.keyframes);
    bone_.push_back(bone);
  }
}

Rigid Colliders::pose(std::size_t k, double t) const {
  return bone_[k] >= 0 ? skeleton_.transform(static_cast<std::size_t>(bone_[k]), t) : tracks_[k].pose(t);
}

std::shared_ptr<ContactTerm> make_contact_term(const ContactParameters& p, const System& system,
                                               std::shared_ptr<const Colliders> colliders) {
  const double h = system.cell_size();
  ContactSettings cs;
  cs.self = p.self;
  cs.stiffness = p.stiffness > 0.0 ? p.stiffness : 10.0 * system.stiffness_scale() / h;
  cs.barrier = p.model == ContactParameters::Model::Barrier;
  // The barrier a tenth as stiff as the springs: its kappa b(d^2) grows without bound as surfaces close
  // anyway, and at 10 (mu_L + lambda_L) / h its energy rose so steeply within dhat that Newton steps
  // closing surfaces were cut to a few percent (docs/performance.md, "A softer barrier").
  if (p.stiffness == 0.0) cs.barrier_stiffness = system.stiffness_scale() / h;
  // The barrier's self contact starts three times farther out than the springs push: at 0.05 h, with
  // edge pairs, the crease behind BCN_Epileptic's knee closed on a cell until a point inverted; at 0.15 h
  // the crease's pairs engage sooner and share the load (docs/performance.md, "A thicker barrier").
  cs.thickness = p.thickness > 0.0 ? p.thickness : (p.self && cs.barrier ? 0.15 : 0.05) * h;
  cs.margin = p.margin > 0.0 ? p.margin : cs.thickness + 0.5 * h;
  if (!(cs.margin > cs.thickness))
    throw InputError("Contact: 'Margin' (" + format_number(cs.margin) + ") must exceed the thickness (" + format_number(cs.thickness) + ")");
  cs.refine = p.refine;
  cs.keep = p.keep;
  cs.rounds = p.rounds;
  cs.onset = p.smooth ? cs.thickness : 0.0;
  cs.edge_pairs = p.edge_pairs;
  auto term = std::make_shared<ContactTerm>(system, cs, colliders->shapes());
  term->set_pose_source([colliders](std::size_t k, double t) { return colliders->pose(k, t); });
  return term;
}

std::shared_ptr<EnergyTerm> Contact::make(const Parameters& p, const TermContext& c) {
  return make_contact_term(p, c.system, std::make_shared<const Colliders>(p, c.skeleton, c.comm, "Contact"));
}

}  // namespace sinew
