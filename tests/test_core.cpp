// Core numerics (Jacobi eigen-solver, rotation-variant SVD and polar decomposition), name matching,
// parameter sections and strict XML reading, and the state machines of the Hessian policy and of the
// preconditioner's lag.
#include "material_test_utils.hpp"

#include <sinew/core/errors.hpp>
#include <sinew/core/parameters.hpp>
#include <sinew/core/validation.hpp>
#include <sinew/core/xml_input.hpp>
#include <sinew/solver/exact_budget.hpp>
#include <sinew/solver/forcing.hpp>
#include <sinew/solver/hessian_policy.hpp>
#include <sinew/solver/preconditioner_lag.hpp>

#include <Teuchos_ParameterList.hpp>
#include <gtest/gtest.h>

#include <map>
#include <sstream>
#include <tuple>

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

// ---------------------------------------------------------------------------------------------
// Parameter sections (core/parameters.hpp) and strict XML reading (core/xml_input.hpp)
// ---------------------------------------------------------------------------------------------
namespace {

struct Leaf {
  double gain = 0.0;
  template <class V>
  void visit(V& v) {
    v.entry("Gain", gain, 2.0, "a gain", Range::positive());
  }
};

struct Section {
  enum class Mode { Slow, Fast };
  int count = 0;
  double ratio = 0.0;
  std::string name;
  std::array<double, 3> axis{};
  std::optional<double> limit;
  Mode mode = Mode::Slow;
  Leaf leaf;
  NamedSections<Leaf> items;
  template <class V>
  void visit(V& v) {
    v.entry("Count", count, 3, "a count", Range::closed(1, 1e6));
    v.entry("Ratio", ratio, 0.5, "a ratio", Range::open(0.0, 1.0));
    v.entry("Name", name, std::string("x"), "a name");
    v.entry("Axis", axis, {0.0, 0.0, 1.0}, "an axis");
    v.optional("Limit", limit, "a limit", Range::non_negative());
    v.choice("Mode", mode, Mode::Slow, Choices<Mode>{{"slow", Mode::Slow}, {"fast", Mode::Fast}}, "a mode");
    v.section("Leaf", leaf, "a fixed sublist");
    v.sections("Items", items, "named sublists");
  }
  void check(const SectionContext& c) const {
    if (count == 13) c.fail("'Count' 13 is unlucky");
  }
};

std::string parse_error(const Teuchos::ParameterList& p) {
  try {
    parse_section<Section>(p, "Test");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Parameters, DefaultsComeFromTheDeclaration) {
  const Section s = default_section<Section>();
  EXPECT_EQ(s.count, 3);
  EXPECT_EQ(s.ratio, 0.5);
  EXPECT_EQ(s.axis[2], 1.0);
  EXPECT_FALSE(s.limit.has_value());
  EXPECT_EQ(s.leaf.gain, 2.0);
  const Section parsed = parse_section<Section>(Teuchos::ParameterList(), "Test");
  EXPECT_EQ(parsed.count, 3);
  const Teuchos::ParameterList valid = declare_section<Section>("Test");
  EXPECT_EQ(valid.get<int>("Count"), 3);
  EXPECT_EQ(valid.sublist("Leaf").get<double>("Gain"), 2.0);
}

TEST(Parameters, ParsesValuesSublistsAndNamedSublistsInOrder) {
  Teuchos::ParameterList p;
  p.set("Count", 7);
  p.set("Axis", Teuchos::Array<double>({1.0, 0.0, 0.0}));
  p.set("Limit", 0.0);
  p.set("Mode", std::string("fast"));
  p.sublist("Leaf").set("Gain", 4.0);
  p.sublist("Items").sublist("zeta").set("Gain", 1.0);
  p.sublist("Items").sublist("alpha");
  const Section s = parse_section<Section>(p, "Test");
  EXPECT_EQ(s.count, 7);
  EXPECT_EQ(s.axis[0], 1.0);
  ASSERT_TRUE(s.limit.has_value());
  EXPECT_EQ(*s.limit, 0.0);
  EXPECT_EQ(s.mode, Section::Mode::Fast);
  EXPECT_EQ(s.leaf.gain, 4.0);
  ASSERT_EQ(s.items.size(), 2u);
  EXPECT_EQ(s.items[0].first, "zeta");  // file order, not alphabetical
  EXPECT_EQ(s.items[0].second.gain, 1.0);
  EXPECT_EQ(s.items[1].second.gain, 2.0);  // default
}

TEST(Parameters, RejectionsNameTheCulprit) {
  auto with = [](auto fill) {
    Teuchos::ParameterList p;
    fill(p);
    return parse_error(p);
  };
  EXPECT_NE(with([](auto& p) { p.set("Count", 0); }).find("Test: 'Count' must lie in [1, 1e6], got 0"), std::string::npos);
  EXPECT_NE(with([](auto& p) { p.set("Ratio", 1.0); }).find("'Ratio' must lie in (0, 1), got 1"), std::string::npos);
  EXPECT_NE(with([](auto& p) { p.set("Ratio", std::nan("")); }).find("'Ratio' must lie in (0, 1), got nan"), std::string::npos);
  EXPECT_NE(with([](auto& p) { p.set("Limit", -1.0); }).find("'Limit' must be >= 0, got -1"), std::string::npos);
  EXPECT_NE(with([](auto& p) { p.set("Count", 2.0); }).find("'Count' in Test has type double, expected int"), std::string::npos);
  EXPECT_NE(with([](auto& p) { p.set("Axis", Teuchos::Array<double>(std::vector<double>{1.0, 2.0})); }).find("'Axis' needs 3 entries, got 2"),
            std::string::npos);
  EXPECT_NE(with([](auto& p) { p.set("Axis", Teuchos::Array<double>({1.0, INFINITY, 0.0})); }).find("'Axis' entries must be finite, got inf"),
            std::string::npos);
  EXPECT_NE(with([](auto& p) { p.set("Mode", std::string("fsat")); }).find("'Mode' must be slow or fast, got \"fsat\" (did you mean \"fast\"?)"),
            std::string::npos);
  EXPECT_NE(with([](auto& p) { p.set("Cuont", 1); }).find("unknown entry 'Cuont' in Test (did you mean 'Count'?)"), std::string::npos);
  EXPECT_NE(with([](auto& p) { p.set("Leaf", 1.0); }).find("'Leaf' in Test must be a sublist"), std::string::npos);
  EXPECT_NE(with([](auto& p) { p.sublist("Count"); }).find("'Count' in Test must be a parameter, not a sublist"), std::string::npos);
  EXPECT_NE(with([](auto& p) { p.sublist("Leaf").set("Gian", 1.0); }).find("unknown entry 'Gian' in Test/Leaf"), std::string::npos);
  EXPECT_NE(with([](auto& p) { p.sublist("Items").set("stray", 1); }).find("Test/Items/stray must be a sublist"), std::string::npos);
  EXPECT_NE(with([](auto& p) { p.sublist("Items").sublist("a").set("Gain", -1.0); }).find("Test/Items/a: 'Gain' must be positive"),
            std::string::npos);
  EXPECT_NE(with([](auto& p) { p.set("Count", 13); }).find("Test: 'Count' 13 is unlucky"), std::string::npos);
}

TEST(Parameters, NumbersAsPeopleWriteThem) {
  EXPECT_EQ(format_number(1e6), "1e6");
  EXPECT_EQ(format_number(100000), "100000");
  EXPECT_EQ(format_number(0.5), "0.5");
  EXPECT_EQ(format_number(-2.5e-7), "-2.5e-7");
  EXPECT_EQ(or_list({"a", "b", "c"}), "a, b or c");
  for (const char* good : {"1", "-2.5e3", " 3 ", ".5", "5.", "+1E-2", "0"}) EXPECT_TRUE(strict_number(good, false)) << good;
  for (const char* bad : {"nan", "NaN", "inf", "-Infinity", "1e", "0x10", "1.0e5x", "", " ", "1e999", "--1", "1,0"})
    EXPECT_FALSE(strict_number(bad, false)) << bad;
  EXPECT_TRUE(strict_number("-12", true));
  for (const char* bad : {"1.5", "99999999999", "1e3", "nan"}) EXPECT_FALSE(strict_number(bad, true)) << bad;
}

TEST(Parameters, FingerprintRecordsEveryEntryWithWhetherItIsItsDefault) {
  Teuchos::ParameterList p;
  p.set("Ratio", 0.1);
  p.set("Mode", std::string("slow"));  // the default, spelled out
  p.sublist("Items").sublist("a=b\nc").set("Gain", 3.0);
  const SectionFingerprint f = section_fingerprint(parse_section<Section>(p, "Test"));
  std::map<std::string, SectionEntry> by;
  for (const auto& e : f.entries) by[e.path] = e;
  EXPECT_EQ(by.at("Count").value, "3");
  EXPECT_TRUE(by.at("Count").at_default);
  EXPECT_EQ(by.at("Ratio").value, "0.1");  // the shortest text that reads back exactly
  EXPECT_FALSE(by.at("Ratio").at_default);
  EXPECT_EQ(by.at("Name").value, "\"x\"");
  EXPECT_EQ(by.at("Axis").value, "{0, 0, 1}");
  EXPECT_TRUE(by.at("Axis").at_default);
  EXPECT_EQ(by.at("Limit").value, "(none)");
  EXPECT_EQ(by.at("Mode").value, "slow");
  EXPECT_TRUE(by.at("Mode").at_default);
  EXPECT_EQ(by.at("Leaf/Gain").value, "2");
  EXPECT_EQ(by.at("Items/a=b\nc/Gain").value, "3");
  // The digest is that of the canonical text alone: recording the entries does not change the text.
  Section parsed = parse_section<Section>(p, "Test");
  std::ostringstream plain, recorded;
  std::vector<SectionEntry> records;
  Fingerprinter without(plain), with(recorded, "", &records);
  parsed.visit(without);
  parsed.visit(with);
  EXPECT_EQ(plain.str(), recorded.str());
  EXPECT_EQ(records.size(), f.entries.size());
  EXPECT_NE(f.digest, section_fingerprint(default_section<Section>()).digest);
  // Names and values with '=', '\' and newlines survive the checkpoint's text.
  const std::vector<SectionEntry> back = decode_entries(encode_entries(f.entries));
  ASSERT_EQ(back.size(), f.entries.size());
  for (std::size_t k = 0; k < back.size(); ++k) {
    EXPECT_EQ(back[k].path, f.entries[k].path);
    EXPECT_EQ(back[k].value, f.entries[k].value);
  }
  const std::vector<SectionEntry> odd{{"a\\b", "x=y\\\n", false}};
  EXPECT_EQ(decode_entries(encode_entries(odd))[0].value, "x=y\\\n");
  EXPECT_EQ(decode_entries(encode_entries(odd))[0].path, "a\\b");
  for (const char* bad : {"a=1", "noequals\n", "a=\\q\n", "a=1\\"}) EXPECT_THROW(decode_entries(bad), std::invalid_argument) << bad;
  for (double x : {0.1, 1.0 / 3.0, 2.5e-7, 1e22, -1234.5, 20000.0}) EXPECT_EQ(std::strtod(round_trip_number(x).c_str(), nullptr), x);
  EXPECT_EQ(round_trip_number(2.5e-7), "2.5e-7");
}

TEST(Parameters, AnEarlierRunsEntriesDifferOnlyWhereTheValuesDoOrANewEntryIsNotAtItsDefault) {
  const std::vector<SectionEntry> stored{{"E", "10000", false}, {"nu", "0.45", false}, {"Old", "1", false}};
  EntryDifference d = compare_entries(stored, {{"nu", "0.45", false}, {"E", "10000", false}, {"Old", "1", true}});
  EXPECT_TRUE(d.differ.empty());  // order does not matter
  EXPECT_TRUE(d.new_at_default.empty());
  d = compare_entries(stored, {{"E", "20000", false}, {"nu", "0.45", false}, {"Old", "1", true}, {"New", "0.8", true}});
  ASSERT_EQ(d.differ.size(), 1u);
  EXPECT_EQ(d.differ[0], "'E' 10000 there, 20000 here");
  ASSERT_EQ(d.new_at_default.size(), 1u);
  EXPECT_EQ(d.new_at_default[0], "'New' (0.8)");
  EXPECT_EQ(compare_entries(stored, {{"E", "20000", false}}, "Material/").differ[0], "'Material/E' 10000 there, 20000 here");
  d = compare_entries(stored, {{"E", "10000", false}, {"nu", "0.45", false}, {"New", "0.5", false}});
  ASSERT_EQ(d.differ.size(), 2u);
  EXPECT_EQ(d.differ[0], "'New' 0.5 here, which that run did not have");
  EXPECT_EQ(d.differ[1], "'Old' 1 there, which this run does not have");
}

TEST(Parameters, StrictXmlReading) {
  auto error = [](const std::string& xml) {
    try {
      read_parameter_text(xml, "t.xml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error("<ParameterList name=\"A\"><Parameter name=\"x\" type=\"double\" value=\"1.5\"/></ParameterList>"), "");
  EXPECT_NE(error("<ParameterList name=\"A\"><Parameter name=\"x\" type=\"Array(double)\" value=\"{nan, 1, 1}\"/></ParameterList>")
                .find("'x' in A is declared Array(double) but its value 'nan' is not a finite number"),
            std::string::npos);
  EXPECT_NE(error("<ParameterList name=\"A\"><Parameter name=\"x\" type=\"int\" value=\"1\"/>"
                  "<Parameter name=\"x\" type=\"int\" value=\"2\"/></ParameterList>")
                .find("entry 'x' appears twice in A"),
            std::string::npos);
  EXPECT_NE(error("<ParameterList name=\"A\"><ParameterList name=\"B\"/><ParameterList name=\"B\"/></ParameterList>")
                .find("entry 'B' appears twice in A"),
            std::string::npos);
  EXPECT_NE(error("<ParameterList name=\"A\">").find("malformed XML"), std::string::npos);
  EXPECT_NE(error("<Other/>").find("the top element is <Other>"), std::string::npos);
}

TEST(HessianPolicy, EveryTransition) {
  HessianPolicy never(0.0);
  never.start(100.0);
  EXPECT_FALSE(never.next_jacobian(1e-9, 0.0));  // 0 disables the exact Hessian

  // Inverted points: exact (the solver's default) and per point go exact while some are inverted, whole mesh
  // does not; only exact gives them their exact Hessian.
  for (auto [inv, exact_when_tangled, at_inverted] :
       {std::tuple{HessianPolicy::Inverted::PerPoint, true, false}, std::tuple{HessianPolicy::Inverted::Exact, true, true},
        std::tuple{HessianPolicy::Inverted::WholeMesh, false, false}}) {
    HessianPolicy q(0.01, inv);
    q.start(100.0);
    EXPECT_EQ(q.next_jacobian(0.5, 0.001), exact_when_tangled);  // a few inverted
    EXPECT_EQ(q.exact_at_inverted(), at_inverted);
    EXPECT_FALSE(q.next_jacobian(0.5, 0.2));  // a tangle of many: projected in every mode
    EXPECT_FALSE(q.next_jacobian(0.5, 0.0, true));  // an undefined point: projected in every mode
  }
  EXPECT_FALSE(HessianPolicy(0.01).exact_at_inverted());

  HessianPolicy p(0.01, HessianPolicy::Inverted::WholeMesh);
  p.start(100.0);
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::Projected);
  EXPECT_FALSE(p.next_jacobian(50.0, 0.0));  // residual not small yet
  EXPECT_FALSE(p.exact_used());
  EXPECT_FALSE(p.next_jacobian(0.5, 0.001));  // small but tangled
  EXPECT_TRUE(p.next_jacobian(0.5, 0.0));  // Projected -> Exact
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::Exact);
  EXPECT_TRUE(p.last_exact());
  EXPECT_TRUE(p.exact_used());
  p.step_taken(1.0);  // a full step keeps it
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::Exact);
  EXPECT_FALSE(p.next_jacobian(5.0, 0.0));  // the residual grew: Exact -> Projected
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::Projected);
  p.line_search_failed();  // a projected direction's failure is not the exact Hessian's fault
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::Projected);
  EXPECT_TRUE(p.next_jacobian(0.5, 0.0));
  p.step_taken(0.25);  // a short step: Exact -> FellBack
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::FellBack);
  EXPECT_FALSE(p.next_jacobian(0.06, 0.0));  // until the residual is ten times below the failure's (0.5)
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::FellBack);
  EXPECT_TRUE(p.retry_projected());
  EXPECT_TRUE(p.next_jacobian(0.04, 0.0));  // FellBack -> Exact
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::Exact);
  EXPECT_TRUE(p.fell_back());  // remembered for the solve's report
  p.line_search_failed();  // failing again: ten times below this failure (0.004) before the next try
  EXPECT_FALSE(p.next_jacobian(0.005, 0.0));
  EXPECT_TRUE(p.next_jacobian(0.003, 0.0));

  p.start(100.0);  // a new solve starts over
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::Projected);
  EXPECT_FALSE(p.fell_back());
  EXPECT_FALSE(p.retry_projected());
  EXPECT_TRUE(p.next_jacobian(0.1, 0.0));
  p.direction_not_descent();  // Exact -> FellBack
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::FellBack);
  p.start(100.0);
  EXPECT_TRUE(p.next_jacobian(0.1, 0.0));
  p.line_search_failed();  // Exact -> FellBack
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::FellBack);
}

// The exact-terms tier (hessian_policy.hpp): off until an exact step is lengthened past long_step (a
// full step is not enough), then every exact Jacobian drops the terms' projections too; a failure of
// one of its directions (not descending, short, CG over budget, failed line search) goes back to the
// exact tier, not to projection, for the rest of the solve; a new solve starts without it; and a policy
// not offered the tier never uses it.
TEST(HessianPolicy, ALengthenedExactStepTurnsOnTheTermsExactHessiansUntilOneOfTheirDirectionsFails) {
  const double lengthened = HessianPolicy::long_step + 0.3;
  for (bool offered : {false, true}) {
    HessianPolicy p(0.01, HessianPolicy::Inverted::Exact);
    p.set_exact_terms(offered);
    for (int failure = 0; failure < 4; ++failure) {
      p.start(100.0);
      EXPECT_TRUE(p.next_jacobian(0.5, 0.0));
      EXPECT_FALSE(p.last_exact_terms());
      p.step_taken(1.0);  // a full step: not yet
      EXPECT_TRUE(p.next_jacobian(0.4, 0.0));
      EXPECT_FALSE(p.last_exact_terms());
      p.step_taken(lengthened);
      EXPECT_TRUE(p.next_jacobian(0.3, 0.0));
      EXPECT_EQ(p.last_exact_terms(), offered);
      p.step_taken(1.0);  // a good step keeps it
      EXPECT_TRUE(p.next_jacobian(0.2, 0.0));
      EXPECT_EQ(p.last_exact_terms(), offered);
      if (!offered) break;
      if (failure == 0) p.direction_not_descent();
      if (failure == 1) p.step_taken(0.25);
      if (failure == 2) p.exact_solve_over_budget();
      if (failure == 3) p.line_search_failed();
      EXPECT_EQ(p.mode(), HessianPolicy::Mode::Exact) << "failure " << failure;  // not FellBack
      EXPECT_FALSE(p.fell_back());
      EXPECT_TRUE(p.next_jacobian(0.2, 0.0));
      EXPECT_FALSE(p.last_exact_terms());
      p.step_taken(lengthened);  // no second try in this solve
      EXPECT_TRUE(p.next_jacobian(0.1, 0.0));
      EXPECT_FALSE(p.last_exact_terms());
      p.step_taken(0.25);  // and the exact tier's own failure falls back as before
      EXPECT_EQ(p.mode(), HessianPolicy::Mode::FellBack);
    }
    p.start(100.0);  // a new solve: off until a lengthened step
    EXPECT_TRUE(p.next_jacobian(0.5, 0.0));
    EXPECT_FALSE(p.last_exact_terms());
  }
  // A projected step lengthened by the line search does not count.
  HessianPolicy q(0.01, HessianPolicy::Inverted::Exact);
  q.set_exact_terms(true);
  q.start(100.0);
  EXPECT_FALSE(q.next_jacobian(50.0, 0.0));
  q.step_taken(lengthened);
  EXPECT_TRUE(q.next_jacobian(0.5, 0.0));
  EXPECT_FALSE(q.last_exact_terms());
}

// Projected Newton near a crease converges linearly, so after a short exact step the exact Hessian is
// tried again after 2, 4, 8, ... projected iterations even where the residual has not dropped ten-fold;
// after a direction that does not descend only the ten-fold drop counts.
TEST(HessianPolicy, AfterAShortExactStepTriesAgainAfterTwoThenFourThenEightProjectedIterations) {
  HessianPolicy p(0.01, HessianPolicy::Inverted::Exact);
  p.start(100.0);
  const double r = 0.5;  // never ten times below a failure: only the count can bring the exact Hessian back
  auto projected_before_exact = [&](int limit) {
    int n = 0;
    while (!p.next_jacobian(r, 0.0) && n < limit) ++n;
    return n;
  };
  EXPECT_TRUE(p.next_jacobian(r, 0.0));
  for (int wait : {2, 4, 8, 16}) {
    p.step_taken(0.25);  // a short step
    EXPECT_EQ(projected_before_exact(100), wait);
    EXPECT_EQ(p.mode(), HessianPolicy::Mode::Exact);
  }
  p.line_search_failed();  // a failed line search counts as a short step: the fifth waits 32
  EXPECT_EQ(projected_before_exact(100), 32);
  // A direction that does not descend at a state with inverted points: not by count.
  EXPECT_TRUE(p.next_jacobian(r, 0.001));
  p.direction_not_descent();
  EXPECT_FALSE(p.saddle());
  int n = 0;
  while (!p.next_jacobian(r, 0.001) && n < 1000) ++n;
  EXPECT_EQ(n, 1000);
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::FellBack);
  EXPECT_TRUE(p.next_jacobian(0.04, 0.001));  // the ten-fold drop still does

  p.start(100.0);  // a new solve waits 2 again
  EXPECT_TRUE(p.next_jacobian(r, 0.0));
  p.step_taken(0.125);
  EXPECT_EQ(projected_before_exact(100), 2);
  // The count never keeps a tangled state exact.
  p.step_taken(0.125);
  for (int k = 0; k < 4; ++k) p.next_jacobian(r, 0.0);
  EXPECT_FALSE(p.next_jacobian(r, 0.2));
}

// An exact solve gets 4 times the CG per digit of the last converged projected solve, times the digits it
// is asked for, at least 100, within the ceiling; before any projected solve, the ceiling.
TEST(ExactSolveBudget, FourTimesTheLastProjectedSolvesRateWithAFloorAndACeiling) {
  ExactSolveBudget b;
  EXPECT_EQ(b.budget(1e-2, 2000), 2000);
  b.projected_solved(28, 1e-2, true);  // 14 per digit
  EXPECT_EQ(b.budget(1e-2, 2000), 112);
  EXPECT_EQ(b.budget(1e-4, 2000), 224);
  EXPECT_EQ(b.budget(1e-4, 150), 150);
  b.projected_solved(500, 1e-2, false);  // a solve that did not converge sets no rate
  EXPECT_EQ(b.budget(1e-2, 2000), 112);
  b.projected_solved(20, 1e-2, true);  // 10 per digit: 80, below the floor
  EXPECT_EQ(b.budget(1e-2, 2000), ExactSolveBudget::min_budget);
  b.projected_solved(2, 1e-2, true);  // 1 per digit: the floor
  EXPECT_EQ(b.budget(1e-2, 2000), ExactSolveBudget::min_budget);
  b.projected_solved(0, 1e-2, true);  // a zero residual's solve keeps the last rate
  EXPECT_EQ(b.budget(1e-2, 2000), ExactSolveBudget::min_budget);
}

// An exact solve over its CG budget falls back as a short step does: projected for 2, then 4, ...
// Jacobians, on the short steps' count.
TEST(HessianPolicy, AnExactSolveOverItsBudgetFallsBackAsAShortStep) {
  HessianPolicy p(0.01, HessianPolicy::Inverted::Exact);
  p.start(100.0);
  EXPECT_TRUE(p.next_jacobian(0.5, 0.0));
  p.exact_solve_over_budget();
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::FellBack);
  EXPECT_TRUE(p.fell_back());
  EXPECT_FALSE(p.saddle());
  EXPECT_FALSE(p.next_jacobian(0.5, 0.0));
  EXPECT_FALSE(p.next_jacobian(0.5, 0.0));
  EXPECT_TRUE(p.next_jacobian(0.5, 0.0));
  p.step_taken(0.25);  // the next short step waits 4: the same count
  for (int k = 0; k < 4; ++k) EXPECT_FALSE(p.next_jacobian(0.5, 0.0));
  EXPECT_TRUE(p.next_jacobian(0.5, 0.0));
  // From the projected Hessian it changes nothing.
  HessianPolicy q(0.01, HessianPolicy::Inverted::Exact);
  q.start(100.0);
  EXPECT_FALSE(q.next_jacobian(50.0, 0.0));
  q.exact_solve_over_budget();
  EXPECT_EQ(q.mode(), HessianPolicy::Mode::Projected);
  EXPECT_FALSE(q.fell_back());
}

// A direction that does not descend where no point is inverted is a saddle of the energy: projected
// Newton slides off it, so the exact Hessian is tried again after 4, 8, 16, ... projected iterations, on
// a count of its own (short steps keep theirs), and the solve remembers the saddle for the line search.
TEST(HessianPolicy, AfterASaddleTriesAgainAfterFourThenEightProjectedIterations) {
  HessianPolicy p(0.01, HessianPolicy::Inverted::PerPoint);
  p.start(100.0);
  const double r = 0.5;
  auto projected_before_exact = [&](int limit) {
    int n = 0;
    while (!p.next_jacobian(r, 0.0) && n < limit) ++n;
    return n;
  };
  EXPECT_TRUE(p.next_jacobian(r, 0.0));
  EXPECT_FALSE(p.saddle());
  for (int wait : {HessianPolicy::saddle_wait, 2 * HessianPolicy::saddle_wait}) {
    p.direction_not_descent();
    EXPECT_TRUE(p.saddle());
    EXPECT_EQ(p.mode(), HessianPolicy::Mode::FellBack);
    EXPECT_EQ(projected_before_exact(100), wait);
  }
  p.step_taken(0.25);  // the first short step of the solve still waits 2
  EXPECT_EQ(projected_before_exact(100), HessianPolicy::first_wait);
  p.direction_not_descent();  // the third saddle 16
  EXPECT_EQ(projected_before_exact(100), 4 * HessianPolicy::saddle_wait);
  // A projected direction that does not descend is no saddle of the exact Hessian's.
  p.start(100.0);
  EXPECT_FALSE(p.next_jacobian(50.0, 0.0));
  p.direction_not_descent();
  EXPECT_FALSE(p.saddle());
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::Projected);
}

// Where the collision test held the last step short of 1, pairs are still closing and the exact Hessian
// (whose barrier pairs have not yet met the faces they approach) gives no quadratic step: it waits for
// a step that was not held, without counting as a fall-back.
TEST(HessianPolicy, WaitsForAStepTheCollisionTestDidNotHold) {
  HessianPolicy p(0.01, HessianPolicy::Inverted::PerPoint);
  p.start(100.0);
  EXPECT_FALSE(p.next_jacobian(0.5, 0.0, false, true));  // small enough, but the last step was held
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::Projected);
  EXPECT_FALSE(p.fell_back());
  EXPECT_FALSE(p.exact_used());
  EXPECT_TRUE(p.next_jacobian(0.5, 0.0, false, false));  // the next step was not held: Exact at once
  EXPECT_TRUE(p.next_jacobian(0.3, 0.0, false, false));
  EXPECT_FALSE(p.next_jacobian(0.3, 0.0, false, true));  // a held step in Exact mode: back to projection
  EXPECT_FALSE(p.fell_back());
  EXPECT_TRUE(p.next_jacobian(0.3, 0.0, false, false));
  // In a fall-back the wait runs as before; a held step only keeps the exact Hessian from coming back.
  p.step_taken(0.25);
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::FellBack);
  EXPECT_FALSE(p.next_jacobian(0.3, 0.0, false, false));
  EXPECT_FALSE(p.next_jacobian(0.3, 0.0, false, false));
  EXPECT_FALSE(p.next_jacobian(0.3, 0.0, false, true));  // the wait of 2 is over, but this step was held
  EXPECT_TRUE(p.next_jacobian(0.3, 0.0, false, false));
}

// A step whose first |F| was small (the tangent predictor's guess, 20): the relative rule alone waits for
// |F| < 0.2, the floor ('Exact Hessian within' times the |F| that ends the solve) allows it below 1 too;
// it changes nothing else (tangles, held steps, fall-backs), and 'Exact Hessian below' 0 still projects.
TEST(HessianPolicy, AlsoExactBelowAnAbsoluteFloorNearConvergence) {
  HessianPolicy relative(0.01, HessianPolicy::Inverted::PerPoint);
  relative.start(20.0);
  EXPECT_FALSE(relative.next_jacobian(0.5, 0.0));
  EXPECT_TRUE(relative.next_jacobian(0.15, 0.0));

  HessianPolicy p(0.01, HessianPolicy::Inverted::PerPoint);
  p.start(20.0);
  p.set_exact_floor(1.0);
  EXPECT_FALSE(p.next_jacobian(1.5, 0.0));        // above both
  EXPECT_TRUE(p.next_jacobian(0.5, 0.0));         // below the floor only
  EXPECT_FALSE(p.next_jacobian(0.5, 0.02));       // tangled: 2% inverted
  EXPECT_FALSE(p.next_jacobian(0.5, 0.0, false, true));  // the last step was held
  EXPECT_TRUE(p.next_jacobian(0.5, 0.0));
  p.step_taken(0.25);                              // a short exact step falls back as before
  EXPECT_EQ(p.mode(), HessianPolicy::Mode::FellBack);
  EXPECT_FALSE(p.next_jacobian(0.5, 0.0));

  HessianPolicy never(0.0);
  never.start(20.0);
  never.set_exact_floor(1.0);
  EXPECT_FALSE(never.next_jacobian(0.5, 0.0));
}

// forcing.hpp: the 969k stretch's third Newton iteration (|F| 1.48, eta 1e-2, threshold 1e-2) is asked
// for half the threshold; far from it, past it, or below the floor the forcing term stands or is floored.
TEST(FinishingTolerance, SolvesToHalfTheThresholdWithinOneDigitOfIt) {
  const double floor = 1e-4;
  EXPECT_NEAR(finishing_tolerance(1e-2, 1.48, 1e-2, floor), 0.5 * 1e-2 / 1.48, 1e-15);
  // eta |F| already below half the threshold: nothing to tighten.
  EXPECT_EQ(finishing_tolerance(1e-2, 0.4, 1e-2, floor), 1e-2);
  // eta |F| = threshold: half of it is one tightening within the digit.
  EXPECT_EQ(finishing_tolerance(1e-2, 1.0, 1e-2, floor), 5e-3);
  // More than a digit away (|F| = 1,000 x threshold would need 5e-4 against eta = 1e-2): the quadratic
  // term dominates there, eta stands.
  EXPECT_EQ(finishing_tolerance(1e-2, 10.0, 1e-2, floor), 1e-2);
  EXPECT_EQ(finishing_tolerance(1e-2, 100.0, 1e-2, floor), 1e-2);
  // Within the digit but below the floor: the floor.
  EXPECT_EQ(finishing_tolerance(1e-3, 2.0, 1e-3, 5e-4), 5e-4);
  // Nothing to end on (the predictor's solve) or nothing measured yet: eta stands.
  EXPECT_EQ(finishing_tolerance(1e-2, 1.48, 0.0, floor), 1e-2);
  EXPECT_EQ(finishing_tolerance(1e-2, 0.0, 1e-2, floor), 1e-2);
}

TEST(PreconditionerLag, EveryTransition) {
  int budget = -1;
  PreconditionerLag every(false, 1.5);  // 'every Newton iteration'
  every.start();
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(every.update(1.0, 1e-2, budget));
    every.solved(10, 1e-2, true, 1.0);
    every.stepped(1.0, 0.0);
  }
  EXPECT_EQ(every.updates(), 3);
  EXPECT_EQ(budget, -1);  // never limited

  PreconditionerLag lag(true, 1.5);
  lag.start();
  EXPECT_TRUE(lag.update(100.0, 1e-2, budget));  // nothing to keep yet
  lag.solved(10, 1e-2, true, 100.0);               // baseline: 5 CG per digit
  lag.stepped(1.0, 0.0);
  EXPECT_FALSE(lag.update(10.0, 1e-2, budget));  // kept
  EXPECT_TRUE(lag.kept());
  EXPECT_EQ(budget, 30);  // 2 x 1.5 x 5 per digit x 2 digits
  EXPECT_FALSE(lag.update(10.0, 1e-4, budget));
  EXPECT_EQ(budget, 60);  // 4 digits asked
  lag.solved(28, 1e-4, true, 10.0);  // 7 per digit, within 1.5 x 5: kept again
  lag.stepped(1.0, 0.0);
  EXPECT_FALSE(lag.update(5.0, 1e-2, budget));
  lag.solved(16, 1e-2, true, 5.0);  // 8 per digit, slower than 1.5 x 5: the next one updates
  lag.stepped(1.0, 0.0);
  EXPECT_TRUE(lag.update(1.0, 1e-2, budget));
  EXPECT_FALSE(lag.kept());
  EXPECT_EQ(lag.updates(), 2);
  lag.solved(2, 1e-2, true, 1.0);  // 1 per digit: the budget never falls below its floor
  lag.stepped(0.5, 0.0);           // a cut step: the next one updates
  EXPECT_TRUE(lag.update(1.0, 1e-2, budget));
  lag.solved(2, 1e-2, true, 1.0);
  lag.stepped(1.0, 0.0);
  EXPECT_FALSE(lag.update(1.0, 1e-2, budget));
  EXPECT_EQ(budget, PreconditionerLag::min_budget);

  // A kept solve over budget: retried at once with an update (RetryingSolve), whose solve sets the new
  // baseline, and nothing kept until the residual is ten times below the failure's.
  const int updates = lag.updates();
  lag.retried(1.0, false);
  EXPECT_FALSE(lag.kept());
  EXPECT_EQ(lag.retries(), 1);
  EXPECT_EQ(lag.updates(), updates + 1);
  lag.solved(10, 1e-2, true, 1.0);  // the repeated solve: 5 per digit
  lag.stepped(1.0, 0.0);
  EXPECT_TRUE(lag.update(0.2, 1e-2, budget));  // not yet ten times below 1.0
  lag.solved(10, 1e-2, true, 0.2);
  lag.stepped(1.0, 0.0);
  EXPECT_FALSE(lag.update(0.05, 1e-2, budget));
  EXPECT_EQ(budget, 30);
  // A kept direction that does not descend is retried too; one retried for an exact Hessian is kept for
  // the next exact one.
  lag.retried(0.05, true);
  lag.solved(10, 1e-2, true, 0.05);
  lag.stepped(1.0, 0.0);
  EXPECT_EQ(lag.retries(), 2);
  EXPECT_FALSE(lag.update(0.001, 1e-2, budget, /*exact=*/true));
  lag.solved(10, 1e-2, true, 0.001);
  // A new solve forgets the failures of the last; a new linear solver forgets the baseline.
  lag.stepped(1.0, 0.0);
  lag.start();
  EXPECT_FALSE(lag.update(50.0, 1e-2, budget));
  lag.solved(10, 1e-2, true, 50.0);
  lag.stepped(1.0, 0.0);
  lag.reset();
  EXPECT_TRUE(lag.update(50.0, 1e-2, budget));
  // A full step that does not halve the residual: the next one updates.
  lag.solved(10, 1e-2, true, 50.0);
  lag.stepped(1.0, 10.0);
  EXPECT_FALSE(lag.update(10.0, 1e-2, budget));
  lag.solved(10, 1e-2, true, 10.0);
  lag.stepped(1.0, 6.0);
  EXPECT_TRUE(lag.update(6.0, 1e-2, budget));
  // One set up for a projected Hessian is not kept for the first exact one; one set up for an exact
  // Hessian is kept for the next exact one and for a projected one after a fall-back.
  lag.solved(10, 1e-2, true, 6.0);
  lag.stepped(1.0, 1.0);
  EXPECT_TRUE(lag.update(1.0, 1e-2, budget, /*exact=*/true));
  lag.solved(10, 1e-2, true, 1.0);
  lag.stepped(1.0, 0.1);
  EXPECT_FALSE(lag.update(0.1, 1e-2, budget, true));
  lag.solved(10, 1e-2, true, 0.1);
  lag.stepped(1.0, 0.01);
  EXPECT_FALSE(lag.update(0.01, 1e-2, budget, false));
}
