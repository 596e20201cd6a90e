// Core numerics: Jacobi eigen-solver, rotation-variant SVD and polar decomposition, validation helpers.
#include "material_test_utils.hpp"

#include <sinew/core/errors.hpp>
#include <sinew/core/validation.hpp>

#include <Teuchos_ParameterList.hpp>
#include <gtest/gtest.h>

using namespace sinew;
using namespace sinew::test;

TEST(Jacobi, MatchesLapackOnRandomSymmetric9x9) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    Mat9 H;
    for (int r = 0; r < 9; ++r)
      for (int c = r; c < 9; ++c) H(r, c) = H(c, r) = n(rng);
    if (trial % 4 == 0)  // repeated eigenvalues: a projector plus identity
      for (int r = 0; r < 9; ++r)
        for (int c = 0; c < 9; ++c) H(r, c) = (r == c ? 2.0 : 0.0) + (r < 3 && c < 3 ? 1.0 : 0.0);
    Mat9 A = H;
    double ev[9], Q[81];
    jacobi_eigen<9>(A.a, ev, Q);
    std::array<double, 9> w;
    std::array<double, 81> Z;
    lapack_eigen(H, w, Z);
    std::sort(ev, ev + 9);
    for (int k = 0; k < 9; ++k) EXPECT_NEAR(ev[k], w[k], 1e-12 * (1.0 + norm(H)));
  }
}

TEST(Svd3, RotationVariantOnAllKinds) {
  std::mt19937_64 rng(2);
  int count = 0;
  for (const auto& s : sample_deformations(rng, 40)) {
    const Svd3 d = svd3(s.F);
    EXPECT_NEAR(det(d.U), 1.0, 1e-12) << s.kind;
    EXPECT_NEAR(det(d.V), 1.0, 1e-12) << s.kind;
    EXPECT_LT(norm(transpose(d.U) * d.U - Mat3::identity()), 1e-12) << s.kind;
    EXPECT_LT(norm(transpose(d.V) * d.V - Mat3::identity()), 1e-12) << s.kind;
    const Mat3 back = d.U * Mat3::diag(d.s[0], d.s[1], d.s[2]) * transpose(d.V);
    EXPECT_LT(norm(back - s.F), 1e-12 * std::max(1.0, norm(s.F))) << s.kind;
    // Sorted up to round-off (repeated singular values come out equal to a few ulps).
    EXPECT_GE(d.s[0], d.s[1] - 1e-14 * d.s[0]);
    EXPECT_GE(d.s[1], std::fabs(d.s[2]) - 1e-14 * d.s[0]);
    EXPECT_EQ(d.s[2] < 0.0, det(s.F) < 0.0) << s.kind;
    ++count;
  }
  EXPECT_GT(count, 200);
}

TEST(Svd3, DegenerateMatrices) {
  const Mat3 cases[] = {Mat3::zero(), Mat3::identity(), Mat3::diag(1, 1, -1), Mat3::diag(2, 0, 0),
                        Mat3::diag(0, 0, 3), Mat3::diag(-1, -1, -1), Mat3::diag(1e-200, 1, 1)};
  for (const Mat3& F : cases) {
    const Svd3 d = svd3(F);
    EXPECT_NEAR(det(d.U), 1.0, 1e-12);
    EXPECT_NEAR(det(d.V), 1.0, 1e-12);
    const Mat3 back = d.U * Mat3::diag(d.s[0], d.s[1], d.s[2]) * transpose(d.V);
    EXPECT_LT(norm(back - F), 1e-13 * std::max(1.0, norm(F)));
    for (double s : d.s) EXPECT_TRUE(std::isfinite(s));
  }
  // Rank one with arbitrary rotation.
  std::mt19937_64 rng(3);
  const Mat3 F = with_singular_values(rng, 2.0, 0.0, 0.0);
  const Svd3 d = svd3(F);
  EXPECT_NEAR(d.s[0], 2.0, 1e-13);
  EXPECT_NEAR(d.s[1], 0.0, 1e-13);
  EXPECT_NEAR(d.s[2], 0.0, 1e-13);
}

TEST(Polar3, RotationTimesSymmetric) {
  std::mt19937_64 rng(4);
  for (const auto& s : sample_deformations(rng, 10)) {
    const Polar3 p = polar3(s.F);
    EXPECT_NEAR(det(p.R), 1.0, 1e-12);
    EXPECT_LT(norm(p.S - transpose(p.S)), 1e-12 * std::max(1.0, norm(s.F)));
    EXPECT_LT(norm(p.R * p.S - s.F), 1e-12 * std::max(1.0, norm(s.F)));
  }
}

TEST(VolumeHessian, MatchesFiniteDifferencesOfCofactor) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  Mat3 F;
  for (int k = 0; k < 9; ++k) F[k] = n(rng);
  Mat9 H = Mat9::zero();
  add_volume_hessian(H, 1.0, F);
  const double h = 1e-6;
  for (int c = 0; c < 9; ++c) {
    Mat3 Fp = F, Fm = F;
    Fp[c] += h;
    Fm[c] -= h;
    const Mat3 d = cofactor(Fp) - cofactor(Fm);
    for (int r = 0; r < 9; ++r) EXPECT_NEAR(H(r, c), d[r] / (2 * h), 1e-8);
  }
}

TEST(Validation, ClosestNameAndUnknownKeys) {
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(closest_name("Poison ratio", {"Poisson ratio", "Young modulus"}), "Poisson ratio");
  EXPECT_EQ(closest_name("banana", {"Poisson ratio", "Young modulus"}), "");
  Teuchos::ParameterList valid, in;
  valid.set("Alpha", 1.0);
  in.set("Alpah", 1.0);
  try {
    require_known_entries(in, valid, "Test");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'Alpha'"), std::string::npos) << e.what();
  }
}
