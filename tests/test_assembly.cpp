// Discretization and assembly: meshes, element data, distributed Tpetra assembly checked against finite
// differences, rigid motions, volumes, Dirichlet elimination, and agreement between backends and ranks.
// Runs as is on 1 rank (unit), with 2 OpenMP threads, and on 2 MPI ranks.
#include "material_test_utils.hpp"
#include "system_test_utils.hpp"
#include "tpetra_test_utils.hpp"

#include <sinew/algebra/system.hpp>
#include <sinew/core/errors.hpp>
#include <sinew/core/hash.hpp>
#include <sinew/discretization/colouring.hpp>

#include <Teuchos_DefaultMpiComm.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_Vector.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <memory>

using namespace sinew;
using namespace sinew::test;

namespace {

auto world() { return Tpetra::getDefaultComm(); }

MaterialSpec material(MaterialModel m = MaterialModel::StableNeoHookean, double E = 1.0, double nu = 0.45,
                      Projection p = Projection::None) {
  MaterialSpec s = test::all_models(E, nu)[static_cast<std::size_t>(m)];
  s.projection = p;
  return s;
}

}  // namespace

TEST(Mesh, CountsOwnershipAndGhosts) {
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    const Mesh m = build_mesh(box(3, type, 4), *world());
    EXPECT_EQ(m.global_nodes, 4 * 4 * 5);
    EXPECT_EQ(m.global_elements, (type == ElementType::Hex8 ? 1 : 6) * 3 * 3 * 4);
    long long owned = static_cast<long long>(m.n_owned_nodes), total = 0;
    Teuchos::reduceAll(*world(), Teuchos::REDUCE_SUM, owned, Teuchos::outArg(total));
    EXPECT_EQ(total, m.global_nodes);
    long long oe = static_cast<long long>(m.n_owned_elements), te = 0;
    Teuchos::reduceAll(*world(), Teuchos::REDUCE_SUM, oe, Teuchos::outArg(te));
    EXPECT_EQ(te, m.global_elements);
    // A rank holds its slab plus at most one ghost layer, not the whole mesh.
    if (world()->getSize() > 1) {
      EXPECT_LT(m.local_nodes(), static_cast<std::size_t>(m.global_nodes));
    }
  }
}

TEST(Mesh, ColouredChunksShareNoNodeWithinAColourAndKeepEveryElementOnce) {
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    const Mesh m = build_mesh(box(5, type, 6), *world());
    auto c = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.conn);
    const int npe = nodes_per_element(type);
    std::vector<int> conn(m.local_elements() * npe), ids;
    for (std::size_t e = 0; e < m.local_elements(); ++e) {
      for (int a = 0; a < npe; ++a) conn[e * npe + a] = c(e, a);
      if (e % 3 != 1) ids.push_back(static_cast<int>(e));  // a sub-list, as a material block is
    }
    for (int chunk : {1, 4, 32, 100000}) {
      const ElementChunks ch = colour_element_chunks(ids, conn, npe, m.local_nodes(), chunk);
      std::vector<int> sorted = ch.elements;
      std::sort(sorted.begin(), sorted.end());
      EXPECT_EQ(sorted, ids) << "chunk " << chunk;
      ASSERT_EQ(ch.chunk_begin.front(), 0);
      ASSERT_EQ(ch.chunk_begin.back(), static_cast<int>(ids.size()));
      ASSERT_EQ(ch.colour_begin.back() + 1, static_cast<int>(ch.chunk_begin.size()));
      for (int k = 0; k < ch.colours(); ++k) {
        std::vector<int> owner(m.local_nodes(), -1);  // the chunk of this colour that touched the node
        for (int q = ch.colour_begin[k]; q < ch.colour_begin[k + 1]; ++q)
          for (int i = ch.chunk_begin[q]; i < ch.chunk_begin[q + 1]; ++i)
            for (int a = 0; a < npe; ++a) {
              int& o = owner[conn[static_cast<std::size_t>(ch.elements[i]) * npe + a]];
              EXPECT_TRUE(o == -1 || o == q) << "colour " << k << ": chunks " << o << " and " << q << " share a node";
              o = q;
            }
      }
      EXPECT_LE(ch.chunk_begin.size() - 1, (ids.size() + chunk - 1) / chunk);
      // One element per chunk on a lattice in lexicographic order: the 8 parity classes of hex8.
      if (chunk == 1 && type == ElementType::Hex8 && world()->getSize() == 1) EXPECT_EQ(ch.colours(), 8);
      if (chunk == 100000) EXPECT_EQ(ch.colours(), 1);
    }
  }
}

TEST(Mesh, VoxelCylinder) {
  MeshSpec s;
  s.shape = MeshType::Cylinder;
  s.cells = {8, 8, 6};
  s.lower = {-1, -1, 0};
  s.upper = {1, 1, 3};
  const Mesh m = build_mesh(s, *world());
  System sys(world(), m, material());
  // The voxelized disk of 8x8 cells keeps the cells whose centres lie inside: 52 of 64.
  EXPECT_EQ(m.global_elements, 52 * 6);
  EXPECT_NEAR(sys.reference_volume(), 52 * (0.25 * 0.25 * 0.5) * 6, 1e-12);
}

TEST(Mesh, RejectsInvertedRestElement) {
  Mesh m = build_mesh(box(2), *world());
  // Move one owned node of the first rank far through its element, collectively.
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.X);
  for (std::size_t n = 0; n < m.local_nodes(); ++n)
    if (m.node_gid[n] == 0) Xh(n, 0) = 5.0;  // node 0 beyond its neighbour at x = 0.5
  Kokkos::deep_copy(m.X, Xh);
  try {
    System sys(world(), m, material());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("element 0 has a non-positive rest volume"), std::string::npos) << e.what();
  }
}

TEST(Assembly, RestStateHasZeroForceAndEnergy) {
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    for (const auto& spec : test::all_models(1.0, 0.45)) {
      System sys(world(), build_mesh(box(3, type), *world()), spec);
      auto u = sys.create_vector();
      u->putScalar(0.0);
      auto f = sys.create_vector();
      const auto t = sys.evaluate(*u, f.get(), nullptr);
      EXPECT_NEAR(t.energy, 0.0, 1e-13) << to_string(spec.model);
      EXPECT_LT(f->normInf(), 1e-13) << to_string(spec.model);
      EXPECT_NEAR(t.volume, 0.96, 1e-12);
      EXPECT_NEAR(t.min_J, 1.0, 1e-14);
    }
  }
}

TEST(Assembly, RigidRotationHasZeroForce) {
  std::mt19937_64 rng(3);
  const Mat3 R = test::random_rotation(rng);
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    for (const auto& spec : test::all_models(1.0, 0.45)) {
      System sys(world(), build_mesh(box(3, type), *world()), spec);
      auto u = sys.create_vector();
      set_displacement(sys, *u, [&](const std::array<double, 3>& X, int c, long long) {
        return R(c, 0) * X[0] + R(c, 1) * X[1] + R(c, 2) * X[2] - X[c];
      });
      auto f = sys.create_vector();
      const auto t = sys.evaluate(*u, f.get(), nullptr);
      EXPECT_NEAR(t.energy, 0.0, 1e-11) << to_string(spec.model);
      EXPECT_LT(f->normInf(), 1e-11) << to_string(spec.model) << " " << to_string(type);
      EXPECT_NEAR(t.volume, 0.96, 1e-12);
    }
  }
}

TEST(Assembly, AffineVolumeEqualsSumOfJ) {
  const double A[3][3] = {{1.2, 0.3, -0.1}, {0.05, 0.9, 0.2}, {0.1, -0.2, 1.1}};
  Mat3 Am;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) Am(i, j) = A[i][j];
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    System sys(world(), build_mesh(box(3, type), *world()), material());
    auto u = sys.create_vector();
    set_displacement(sys, *u, [&](const std::array<double, 3>& X, int c, long long) {
      return A[c][0] * X[0] + A[c][1] * X[1] + A[c][2] * X[2] - X[c];
    });
    const auto t = sys.evaluate(*u, nullptr, nullptr);
    EXPECT_NEAR(t.volume, det(Am) * 0.96, 1e-12);
    EXPECT_NEAR(t.min_J, det(Am), 1e-12);
  }
}

TEST(Assembly, ForceIsGradientOfEnergy) {
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    for (const auto& spec0 : test::all_models(1.0, 0.45)) {
      if (type == ElementType::Tet4 && spec0.model != MaterialModel::StableNeoHookean &&
          spec0.model != MaterialModel::Corotational)
        continue;
      System sys(world(), build_mesh(box(2, type), *world()), spec0);
      auto u = sys.create_vector();
      set_displacement(sys, *u, [&](const std::array<double, 3>&, int c, long long g) { return 0.12 * hash_unit(g, c); });
      auto f = sys.create_vector();
      sys.evaluate(*u, f.get(), nullptr);
      const auto fg = gather(*f);
      const double h = 1e-6;
      double worst = 0.0, fmax = 0.0;
      for (GO j = 0; j < static_cast<GO>(fg.size()); ++j) {
        const bool mine = sys.owned_dofs()->isNodeGlobalElement(j);
        double e[2];
        for (int s = 0; s < 2; ++s) {
          if (mine) u->sumIntoGlobalValue(j, s == 0 ? h : -2.0 * h);
          e[s] = sys.evaluate(*u, nullptr, nullptr).energy;
        }
        if (mine) u->sumIntoGlobalValue(j, h);
        worst = std::max(worst, std::fabs((e[0] - e[1]) / (2 * h) - fg[j]));
        fmax = std::max(fmax, std::fabs(fg[j]));
      }
      EXPECT_LT(worst, 1e-6 * std::max(fmax, 1.0)) << to_string(spec0.model) << " " << to_string(type);
      if (world()->getRank() == 0 && spec0.model == MaterialModel::StableNeoHookean)
        std::printf("[ info ] %s SNH: |force - FD(energy)|max = %.2e, |force|max = %.2e\n", to_string(type).c_str(), worst, fmax);
    }
  }
}

TEST(Assembly, MatrixIsJacobianOfForceAndProjectionIsPsd) {
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    for (const auto& spec0 : test::all_models(1.0, 0.45)) {
      if (type == ElementType::Tet4 && spec0.model != MaterialModel::StableNeoHookean) continue;
      MaterialSpec spec = spec0;
      spec.projection = Projection::None;
      System sys(world(), build_mesh(box(2, type), *world()), spec);
      auto u = sys.create_vector();
      set_displacement(sys, *u, [&](const std::array<double, 3>& X, int c, long long g) {
        return 0.1 * hash_unit(g, c) - (c == 2 ? 0.6 * X[2] : 0.0);  // distorted and strongly compressed
      });
      auto K = sys.create_matrix();
      sys.evaluate(*u, nullptr, K.get());
      const auto D = dense(*K);
      const std::size_t n = D.size();
      auto fp = sys.create_vector(), fm = sys.create_vector();
      const double h = 1e-6;
      double worst = 0.0;
      for (GO j = 0; j < static_cast<GO>(n); ++j) {
        const bool mine = sys.owned_dofs()->isNodeGlobalElement(j);
        if (mine) u->sumIntoGlobalValue(j, h);
        sys.evaluate(*u, fp.get(), nullptr);
        if (mine) u->sumIntoGlobalValue(j, -2 * h);
        sys.evaluate(*u, fm.get(), nullptr);
        if (mine) u->sumIntoGlobalValue(j, h);
        const auto a = gather(*fp), b = gather(*fm);
        for (std::size_t i = 0; i < n; ++i) worst = std::max(worst, std::fabs((a[i] - b[i]) / (2 * h) - D[i][j]));
      }
      const double scale = max_abs(D);
      EXPECT_LT(worst, 1e-6 * scale) << to_string(spec.model) << " " << to_string(type);
      if (world()->getRank() == 0 && spec.model == MaterialModel::StableNeoHookean)
        std::printf("[ info ] %s SNH: |K - FD(force)|max / |K|max = %.2e\n", to_string(type).c_str(), worst / scale);
      // Symmetric.
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 0; k < n; ++k) ASSERT_NEAR(D[i][k], D[k][i], 1e-12 * scale);
      // The clamped projection of the same state is PSD even where the exact matrix is not.
      auto Kp = sys.create_matrix();
      sys.evaluate(*u, nullptr, Kp.get(), Backend::Default, Projection::Clamp);
      const double lmin = min_eigenvalue(dense(*Kp));
      EXPECT_GE(lmin, -1e-12 * scale) << to_string(spec.model);
    }
  }
}

TEST(Assembly, ClampedEqualsExactWhereNothingIsClamped) {
  // At rest every element Hessian is PSD (its only zero eigenvalues are the rotations), so the
  // projection must change nothing.
  System sys(world(), build_mesh(box(3), *world()), material(MaterialModel::StableNeoHookean, 1.0, 0.45));
  auto u = sys.create_vector();
  u->putScalar(0.0);
  auto K0 = sys.create_matrix(), K1 = sys.create_matrix();
  sys.evaluate(*u, nullptr, K0.get());
  sys.evaluate(*u, nullptr, K1.get(), Backend::Default, Projection::Clamp);
  const auto a = dense(*K0), b = dense(*K1);
  double d = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < a.size(); ++j) d = std::max(d, std::fabs(a[i][j] - b[i][j]));
  EXPECT_LT(d, 1e-12 * max_abs(a));
}

// "Exact where not inverted" (the solver's choice near convergence with a few inverted points) is the
// exact Hessian where no point is inverted, and the clamped one where every point is (a mirror image:
// F = diag(-1, 1, 1)); a twisted state in between differs from both.
TEST(Assembly, ExactWhereUninvertedIsPerPoint) {
  System sys(world(), build_mesh(box(3), *world()), material(MaterialModel::StableNeoHookean, 1.0, 0.45, Projection::Clamp));
  auto u = sys.create_vector();
  auto diff = [&](std::optional<Projection> a, std::optional<Projection> b) {
    auto Ka = sys.create_matrix(), Kb = sys.create_matrix();
    sys.evaluate(*u, nullptr, Ka.get(), Backend::Default, a);
    sys.evaluate(*u, nullptr, Kb.get(), Backend::Default, b);
    const auto A = dense(*Ka), B = dense(*Kb);
    double d = 0.0;
    for (std::size_t i = 0; i < A.size(); ++i)
      for (std::size_t j = 0; j < A.size(); ++j) d = std::max(d, std::fabs(A[i][j] - B[i][j]));
    return d / max_abs(A);
  };
  const auto mixed = Projection::ExactUninvertedClamp;
  // Compressed and sheared, nowhere inverted: exact, and indefinite (so clamping changes it).
  set_displacement(sys, *u, [](const std::array<double, 3>& X, int c, long long) { return c == 0 ? -0.6 * X[0] + 0.5 * X[2] : 0.0; });
  ASSERT_EQ(sys.evaluate(*u, nullptr, nullptr).inverted, 0);
  EXPECT_LT(diff(mixed, Projection::None), 1e-14);
  EXPECT_GT(diff(Projection::Clamp, Projection::None), 1e-3);
  // Mirrored: every point inverted, clamped.
  set_displacement(sys, *u, [](const std::array<double, 3>& X, int c, long long) { return c == 0 ? -2.0 * X[0] : 0.0; });
  ASSERT_GT(sys.evaluate(*u, nullptr, nullptr).inverted, 0);
  EXPECT_LT(diff(mixed, Projection::Clamp), 1e-14);
  EXPECT_GT(diff(Projection::Clamp, Projection::None), 1e-3);
}

// Mean dilatation (materials/mean_dilatation.hpp), the whole volume term on the mean (share 1) or part
// of it (0.8, the option's default): the same law as the paper's element under an affine motion, another
// element under a non-affine one; force the gradient of the energy, the exact matrix the Jacobian of the
// force, the clamped one PSD; on a tet4 (one point) the same element.
TEST(Assembly, MeanDilatationIsConsistentPsdAndTheLawUnderAffineMotion) {
  for (auto model : {MaterialModel::StableNeoHookean, MaterialModel::StableNeoHookeanNoBarrier})
  for (double share : {1.0, 0.8}) {
    MaterialSpec plain = material(model, 1.0, 0.49), md = plain;
    md.mean_dilatation = share;
    char tag[32];
    std::snprintf(tag, sizeof tag, " share %g", share);
    const std::string name = to_string(model) + tag;
    auto max_abs_diff = [](const std::vector<double>& x, const std::vector<double>& y) {
      double d = 0.0;
      for (std::size_t i = 0; i < x.size(); ++i) d = std::max(d, std::fabs(x[i] - y[i]));
      return d;
    };
    auto energy_and_force = [&](const MaterialSpec& spec, ElementType type, auto&& disp) {
      System sys(world(), build_mesh(box(2, type), *world()), spec);
      auto u = sys.create_vector();
      set_displacement(sys, *u, disp);
      auto f = sys.create_vector();
      const double e = sys.evaluate(*u, f.get(), nullptr).energy;
      return std::make_pair(e, gather(*f));
    };
    auto affine = [](const std::array<double, 3>& X, int c, long long) {
      const double A[3][3] = {{0.2, 0.3, -0.1}, {0.05, -0.3, 0.2}, {0.1, -0.2, 0.15}};
      return A[c][0] * X[0] + A[c][1] * X[1] + A[c][2] * X[2];
    };
    auto distorted = [](const std::array<double, 3>& X, int c, long long g) {
      return 0.1 * hash_unit(g, c) - (c == 2 ? 0.4 * X[2] : 0.0);
    };
    for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
      const auto a = energy_and_force(plain, type, affine), b = energy_and_force(md, type, affine);
      EXPECT_NEAR(a.first, b.first, 1e-12 * std::fabs(a.first)) << name << " affine " << to_string(type);
      EXPECT_LT(max_abs_diff(a.second, b.second), 1e-11) << name << " affine " << to_string(type);
      const auto c = energy_and_force(plain, type, distorted), d = energy_and_force(md, type, distorted);
      if (type == ElementType::Tet4) {
        EXPECT_NEAR(c.first, d.first, 1e-12 * std::fabs(c.first)) << name;
        EXPECT_LT(max_abs_diff(c.second, d.second), 1e-11) << name;
      } else {
        EXPECT_GT(std::fabs(c.first - d.first), 1e-3 * std::fabs(c.first)) << name << ": the option changed nothing";
        if (share < 1.0) {
          // The energy is linear in the share: (1 - s) x the paper's element + s x the pure mean dilatation.
          MaterialSpec pure = md;
          pure.mean_dilatation = 1.0;
          const auto m = energy_and_force(pure, type, distorted);
          std::vector<double> mix(c.second.size());
          for (std::size_t i = 0; i < mix.size(); ++i) mix[i] = (1.0 - share) * c.second[i] + share * m.second[i];
          EXPECT_NEAR(d.first, (1.0 - share) * c.first + share * m.first, 1e-12 * std::fabs(c.first)) << name;
          EXPECT_LT(max_abs_diff(d.second, mix), 1e-11) << name;
        }
      }
    }
    // Derivatives on the distorted, strongly compressed hex8 state.
    System sys(world(), build_mesh(box(2), *world()), md);
    auto u = sys.create_vector();
    set_displacement(sys, *u, distorted);
    auto f = sys.create_vector();
    auto K = sys.create_matrix();
    sys.evaluate(*u, f.get(), K.get());
    const auto fg = gather(*f);
    const auto D = dense(*K);
    const std::size_t n = D.size();
    auto fp = sys.create_vector(), fm = sys.create_vector();
    const double h = 1e-6;
    double worst_f = 0.0, worst_K = 0.0;
    for (GO j = 0; j < static_cast<GO>(n); ++j) {
      const bool mine = sys.owned_dofs()->isNodeGlobalElement(j);
      if (mine) u->sumIntoGlobalValue(j, h);
      const double ep = sys.evaluate(*u, fp.get(), nullptr).energy;
      if (mine) u->sumIntoGlobalValue(j, -2 * h);
      const double em = sys.evaluate(*u, fm.get(), nullptr).energy;
      if (mine) u->sumIntoGlobalValue(j, h);
      worst_f = std::max(worst_f, std::fabs((ep - em) / (2 * h) - fg[j]));
      const auto a = gather(*fp), b = gather(*fm);
      for (std::size_t i = 0; i < n; ++i) worst_K = std::max(worst_K, std::fabs((a[i] - b[i]) / (2 * h) - D[i][j]));
    }
    double fmax = 0.0;
    for (double x : fg) fmax = std::max(fmax, std::fabs(x));
    const double scale = max_abs(D);
    EXPECT_LT(worst_f, 1e-6 * std::max(fmax, 1.0)) << name;
    EXPECT_LT(worst_K, 1e-6 * scale) << name;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = 0; k < n; ++k) ASSERT_NEAR(D[i][k], D[k][i], 1e-12 * scale) << name;
    auto Kp = sys.create_matrix();
    sys.evaluate(*u, nullptr, Kp.get(), Backend::Default, Projection::Clamp);
    const double lmin = min_eigenvalue(dense(*Kp));
    EXPECT_GE(lmin, -1e-12 * scale) << name;
    if (world()->getRank() == 0)
      std::printf("[ info ] hex8 %s, mean dilatation: |f - FD(E)| = %.2e, |K - FD(f)| / |K| = %.2e, clamped min eig %.2e\n",
                  name.c_str(), worst_f, worst_K / scale, lmin / scale);
  }
}

TEST(Assembly, RigidBodyModesSpanRestNullSpace) {
  System sys(world(), build_mesh(box(3), *world()), material());
  auto u = sys.create_vector();
  u->putScalar(0.0);
  auto K = sys.create_matrix();
  sys.evaluate(*u, nullptr, K.get());
  auto modes = sys.rigid_body_modes();
  MultiVector Km(sys.owned_dofs(), 6);
  K->apply(*modes, Km);
  std::vector<double> kn(6), mn(6);
  Km.normInf(kn);
  modes->normInf(mn);
  const double knorm = K->getFrobeniusNorm();
  for (int k = 0; k < 6; ++k) EXPECT_LT(kn[k], 1e-12 * knorm * mn[k]) << "mode " << k;
  EXPECT_EQ(sys.coordinates()->getNumVectors(), 3u);
}

TEST(Assembly, DirichletEliminationIsSymmetric) {
  System sys(world(), build_mesh(box(2), *world()), material(MaterialModel::StableNeoHookean, 1.0, 0.45, Projection::Clamp));
  std::vector<int> fixed;
  for (int n : select_nodes(sys.mesh(), face_predicate(sys.mesh(), "z-")))
    for (int c = 0; c < 3; ++c) fixed.push_back(3 * n + c);
  sys.set_fixed_dofs(fixed);
  EXPECT_EQ(sys.global_fixed_dofs(), 27u);
  auto u = sys.create_vector();
  set_displacement(sys, *u, [&](const std::array<double, 3>&, int c, long long g) { return 0.05 * hash_unit(g, c); });
  auto f = sys.create_vector();
  auto K = sys.create_matrix();
  sys.evaluate(*u, f.get(), K.get());
  const auto D = dense(*K);
  const auto fg = gather(*f);
  // Global ids of fixed DOFs: nodes on z = 0 are the first 9 node ids (layer 0).
  for (std::size_t i = 0; i < D.size(); ++i) {
    const bool fi = i < 27;
    if (fi) {
      EXPECT_EQ(fg[i], 0.0);
      EXPECT_GT(D[i][i], 0.0);
    }
    for (std::size_t j = 0; j < D.size(); ++j) {
      EXPECT_NEAR(D[i][j], D[j][i], 1e-13);
      if ((fi || j < 27) && i != j) {
        EXPECT_EQ(D[i][j], 0.0);
      }
    }
  }
  EXPECT_GT(min_eigenvalue(D), 0.0);  // fixing a face removes the rigid modes
}

TEST(Assembly, TheLiftedForceIsTheForceLinearisedAlongThePrescribedIncrement) {
  // evaluate_lifted(u, d): f(u) + K(u) d in the free rows (d non-zero in the fixed rows only), zero in
  // the fixed rows, and K as evaluate() leaves it. Checked against a central difference of the force
  // along d, whose free rows need the couplings to the fixed DOFs that the elimination removes.
  System sys(world(), build_mesh(box(3), *world()), material(MaterialModel::StableNeoHookean, 1.0, 0.45, Projection::Clamp));
  std::vector<int> fixed;
  for (const char* face : {"z-", "z+"})
    for (int n : select_nodes(sys.mesh(), face_predicate(sys.mesh(), face)))
      for (int c = 0; c < 3; ++c) fixed.push_back(3 * n + c);
  sys.set_fixed_dofs(fixed);
  auto u = sys.create_vector(), d = sys.create_vector();
  set_displacement(sys, *u, [&](const std::array<double, 3>&, int c, long long g) { return 0.05 * hash_unit(g, c); });
  d->putScalar(0.0);
  {
    auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.mesh().X);
    auto v = d->getLocalViewHost(Tpetra::Access::ReadWrite);
    for (int i : sys.fixed_owned_dofs()) v(i, 0) = X(i / 3, 2) > 0.5 ? 0.1 * (1 + i % 3) : 0.0;  // the top face moves
  }
  auto lifted = sys.create_vector(), f = sys.create_vector(), fp = sys.create_vector(), fm = sys.create_vector();
  auto K = sys.create_matrix(), K0 = sys.create_matrix();
  // The exact Hessian: the difference quotient knows nothing of projections.
  sys.evaluate_lifted(*u, *d, *lifted, *K, Projection::None);
  sys.evaluate(*u, f.get(), K0.get(), Backend::Default, Projection::None);
  const double h = 1e-6;
  auto up = sys.create_vector(), um = sys.create_vector();
  up->update(1.0, *u, h, *d, 0.0);
  um->update(1.0, *u, -h, *d, 0.0);
  sys.gradient(*up, *fp);
  sys.gradient(*um, *fm);
  const auto lg = gather(*lifted), fg = gather(*f), pg = gather(*fp), mg = gather(*fm);
  const std::vector<char> is_fixed = fixed_flags(sys);
  double scale = 0.0, worst = 0.0, lift = 0.0;
  for (std::size_t i = 0; i < lg.size(); ++i) {
    if (is_fixed[i]) {
      EXPECT_EQ(lg[i], 0.0) << i;
      continue;
    }
    const double expected = fg[i] + (pg[i] - mg[i]) / (2 * h);
    scale = std::max(scale, std::fabs(expected));
    lift = std::max(lift, std::fabs(expected - fg[i]));
    worst = std::max(worst, std::fabs(lg[i] - expected));
  }
  EXPECT_GT(lift, 1e-3 * scale);  // the increment matters: the test could fail
  EXPECT_LT(worst, 1e-7 * scale) << "lifted force against f + (f(u + h d) - f(u - h d)) / 2h";
  const auto D = dense(*K), D0 = dense(*K0);
  double apart = 0.0;
  for (std::size_t i = 0; i < D.size(); ++i)
    for (std::size_t j = 0; j < D.size(); ++j) apart = std::max(apart, std::fabs(D[i][j] - D0[i][j]));
  EXPECT_EQ(apart, 0.0);  // the same eliminated matrix as evaluate()'s
}

TEST(Assembly, ColouredScatterAddsWhatAtomicAddsAndTheSameBitsOnEveryBackend) {
  // The element loop without atomics (coloured chunks, ElementLoop::chunks) against the one with an
  // atomic add per entry (SINEW_ASSEMBLY_CHUNK=0): the same sums to round-off. And since no two threads
  // ever add into one entry, the order of the sums no longer depends on the threads: Serial and OpenMP
  // give the same bits.
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    const auto spec = material(MaterialModel::StableNeoHookean, 1.0, 0.45, Projection::Clamp);
    auto make = [&](const char* chunk) {
      if (chunk) setenv("SINEW_ASSEMBLY_CHUNK", chunk, 1);
      auto s = std::make_unique<System>(world(), build_mesh(box(6, type), *world()), spec);
      unsetenv("SINEW_ASSEMBLY_CHUNK");
      return s;
    };
    for (const char* chunk : {static_cast<const char*>(nullptr), "3"}) {
      auto coloured = make(chunk), atomic = make("0");
      auto u = coloured->create_vector(), ua = atomic->create_vector();
      for (auto [s, v] : {std::pair{coloured.get(), u.get()}, std::pair{atomic.get(), ua.get()}})
        set_displacement(*s, *v, [&](const std::array<double, 3>& X, int c, long long g) {
          return 0.1 * hash_unit(g, c, 7) + (c == 1 ? 0.4 * X[0] * X[2] : 0.0);
        });
      auto f = coloured->create_vector(), fser = coloured->create_vector(), fa = atomic->create_vector();
      auto K = coloured->create_matrix(), Kser = coloured->create_matrix(), Ka = atomic->create_matrix();
      coloured->evaluate(*u, f.get(), K.get());
      coloured->evaluate(*u, fser.get(), Kser.get(), Backend::Serial);
      atomic->evaluate(*ua, fa.get(), Ka.get());
      const auto x = K->getLocalMatrixHost().values, xs = Kser->getLocalMatrixHost().values,
                 xa = Ka->getLocalMatrixHost().values;
      ASSERT_EQ(x.extent(0), xa.extent(0));
      double kmax = 0.0, dk = 0.0;
      std::size_t differ = 0;
      for (std::size_t i = 0; i < x.extent(0); ++i) {
        differ += x(i) != xs(i);
        kmax = std::max(kmax, std::fabs(xa(i)));
        dk = std::max(dk, std::fabs(x(i) - xa(i)));
      }
      EXPECT_EQ(differ, 0u) << "matrix entries that differ between Serial and OpenMP";
      EXPECT_LT(dk, 1e-13 * kmax);
      EXPECT_GT(kmax, 0.0);
      const auto a = f->getLocalViewHost(Tpetra::Access::ReadOnly), b = fser->getLocalViewHost(Tpetra::Access::ReadOnly),
                 c = fa->getLocalViewHost(Tpetra::Access::ReadOnly);
      double fmax = 0.0, df = 0.0;
      for (std::size_t i = 0; i < a.extent(0); ++i) {
        EXPECT_EQ(a(i, 0), b(i, 0)) << "force entry " << i;
        fmax = std::max(fmax, std::fabs(c(i, 0)));
        df = std::max(df, std::fabs(a(i, 0) - c(i, 0)));
      }
      EXPECT_LT(df, 1e-13 * fmax);
    }
  }
}

TEST(Assembly, AffineHex8KeepsOneInverseJacobianPerElementAndAssemblesWhatStoredGradientsDo) {
  // A hex8 mesh of parallelepipeds (here a lattice under a shear and stretch) keeps one inverse
  // Jacobian per element instead of dN/dX per point (72 bytes instead of 1.5 kB); the assembled matrix
  // and force agree with the stored gradients' to round-off. A mesh with one curved element, and tet4,
  // store dN/dX per point.
  const auto spec = material(MaterialModel::StableNeoHookean, 1.0, 0.45, Projection::Clamp);
  for (auto type : {ElementType::Hex8, ElementType::Tet4})
    for (bool affine : {true, false}) {
      auto mesh_of = [&] {
        Mesh mesh = build_mesh(box(4, type), *world());
        auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
        for (std::size_t n = 0; n < X.extent(0); ++n) {
          const double x = X(n, 0), y = X(n, 1), z = X(n, 2);
          X(n, 0) = 1.3 * x + 0.4 * y - 0.2 * z + 0.1;
          X(n, 1) = 0.9 * y + 0.3 * z;
          X(n, 2) = 1.1 * z - 0.25 * x;
          // A nudge of one node makes its elements non-affine.
          if (!affine && mesh.node_gid[n] == 7) X(n, 0) += 0.02;
        }
        Kokkos::deep_copy(mesh.X, X);
        return mesh;
      };
      const Mesh probe = mesh_of();
      const ElementData ed = compute_element_data(probe, *world());
      const bool per_element = type == ElementType::Hex8 && (affine || probe.local_elements() == 0 ||
                                                             [&] {  // a rank without the nudged node
                                                               for (GlobalId g : probe.node_gid)
                                                                 if (g == 7) return false;
                                                               return true;
                                                             }());
      EXPECT_EQ(ed.Jinv.extent(0), per_element ? probe.local_elements() : 0u);
      EXPECT_EQ(ed.dNdX.extent(0), per_element ? 0u : probe.local_elements() * ed.nqp);
      std::vector<std::vector<double>> K, f;
      for (const char* store : {"1", "0"}) {
        setenv("SINEW_STORE_GRADIENTS", store, 1);
        System s(world(), mesh_of(), spec);
        unsetenv("SINEW_STORE_GRADIENTS");
        auto u = s.create_vector(), r = s.create_vector();
        set_displacement(s, *u, [&](const std::array<double, 3>& X, int c, long long g) {
          return 0.1 * hash_unit(g, c, 5) + (c == 2 ? 0.3 * X[0] * X[1] : 0.0);
        });
        auto A = s.create_matrix();
        s.evaluate(*u, r.get(), A.get());
        const auto v = A->getLocalMatrixHost().values;
        K.emplace_back(v.data(), v.data() + v.extent(0));
        f.push_back(gather(*r));
      }
      ASSERT_EQ(K[0].size(), K[1].size());
      double kmax = 0.0, dk = 0.0, fmax = 0.0, df = 0.0;
      for (std::size_t i = 0; i < K[0].size(); ++i) {
        kmax = std::max(kmax, std::fabs(K[0][i]));
        dk = std::max(dk, std::fabs(K[0][i] - K[1][i]));
      }
      for (std::size_t i = 0; i < f[0].size(); ++i) {
        fmax = std::max(fmax, std::fabs(f[0][i]));
        df = std::max(df, std::fabs(f[0][i] - f[1][i]));
      }
      EXPECT_GT(kmax, 0.0);
      EXPECT_LE(dk, 1e-13 * kmax) << "affine " << affine;
      EXPECT_LE(df, 1e-13 * fmax) << "affine " << affine;
    }
}

TEST(Assembly, BackendsAndRanksAgree) {
  // Serial execution space vs the default one (OpenMP with the threads this test got), and the
  // distributed assembly vs a one-rank assembly of the whole mesh on every rank.
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    const auto spec = material(MaterialModel::StableNeoHookean, 1.0, 0.45, Projection::Clamp);
    auto self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
    System dist(world(), build_mesh(box(4, type), *world()), spec);
    System solo(self, build_mesh(box(4, type), *self), spec);
    auto fill = [](const System& s, Vector& u) {
      set_displacement(s, u, [&](const std::array<double, 3>& X, int c, long long g) {
        return 0.08 * hash_unit(g, c, 1) + (c == 0 ? 0.3 * X[2] * X[1] : 0.0);
      });
    };
    auto ud = dist.create_vector(), us = solo.create_vector();
    fill(dist, *ud);
    fill(solo, *us);
    auto fd = dist.create_vector(), fs = solo.create_vector(), fser = dist.create_vector();
    auto Kd = dist.create_matrix(), Ks = solo.create_matrix(), Kser = dist.create_matrix();
    const auto td = dist.evaluate(*ud, fd.get(), Kd.get());
    const auto ts = solo.evaluate(*us, fs.get(), Ks.get());
    const auto tser = dist.evaluate(*ud, fser.get(), Kser.get(), Backend::Serial);
    const double e_scale = std::max(1.0, std::fabs(ts.energy));
    EXPECT_NEAR(td.energy, ts.energy, 1e-12 * e_scale);
    EXPECT_NEAR(tser.energy, ts.energy, 1e-12 * e_scale);
    EXPECT_NEAR(td.volume, ts.volume, 1e-12);
    EXPECT_EQ(td.min_J, ts.min_J);
    const auto a = gather(*fd), b = gather(*fs), c = gather(*fser);
    double fmax = 0.0, dab = 0.0, dcb = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      fmax = std::max(fmax, std::fabs(b[i]));
      dab = std::max(dab, std::fabs(a[i] - b[i]));
      dcb = std::max(dcb, std::fabs(c[i] - b[i]));
    }
    EXPECT_LT(dab, 1e-12 * fmax);
    EXPECT_LT(dcb, 1e-12 * fmax);
    const double kd = Kd->getFrobeniusNorm(), ks = Ks->getFrobeniusNorm(), kser = Kser->getFrobeniusNorm();
    EXPECT_NEAR(kd, ks, 1e-12 * ks);
    EXPECT_NEAR(kser, ks, 1e-12 * ks);
    // Entry by entry through a product with a deterministic vector.
    auto x = dist.create_vector(), xs = solo.create_vector();
    fill(dist, *x);
    fill(solo, *xs);
    auto yd = dist.create_vector(), ys = solo.create_vector();
    Kd->apply(*x, *yd);
    Ks->apply(*xs, *ys);
    const auto p = gather(*yd), q = gather(*ys);
    double dy = 0.0, ymax = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      dy = std::max(dy, std::fabs(p[i] - q[i]));
      ymax = std::max(ymax, std::fabs(q[i]));
    }
    EXPECT_LT(dy, 1e-12 * ymax);
  }
}
