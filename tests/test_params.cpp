// The parameter table: one declaration per parameter (defaults come from the table, every member has an
// entry), unique keys, defaults in range, validation of values and relations, KEY=VALUE assignments.
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <new>
#include <set>

#include "sim/params.h"

using namespace fp::sim;

TEST(ParamTableTest, KeysAreUniqueAndDefaultsInRange) {
  const SimParams defaults;
  std::set<std::string> keys;
  for (const ParamInfo& e : ParamTable::sim().entries()) {
    EXPECT_TRUE(keys.insert(e.key).second) << e.key;
    EXPECT_FALSE(e.description.empty()) << e.key;
    EXPECT_FALSE(e.unit.empty()) << e.key;
    EXPECT_LE(e.min, e.max) << e.key;
    if (e.kind == ParamKind::Vector3) {
      for (double c : ParamTable::getVec3(defaults, e)) {
        EXPECT_GE(c, e.min) << e.key;
        EXPECT_LE(c, e.max) << e.key;
      }
    } else {
      const double v = ParamTable::getScalar(defaults, e);
      EXPECT_GE(v, e.min) << e.key;
      EXPECT_LE(v, e.max) << e.key;
    }
  }
  EXPECT_GE(keys.size(), 15u);
  EXPECT_EQ(ParamTable::validate(defaults), "");
}

TEST(ParamTableTest, SetsAndRejectsValues) {
  SimParams p;
  const ParamTable& t = ParamTable::sim();
  const ParamInfo* radius = t.find("particle_radius");
  ASSERT_NE(radius, nullptr);
  EXPECT_EQ(ParamTable::setScalar(p, *radius, 0.01), "");
  EXPECT_DOUBLE_EQ(p.particleRadius, 0.01);
  const std::string err = ParamTable::setScalar(p, *radius, -1.0);
  EXPECT_NE(err.find("particle_radius"), std::string::npos);
  EXPECT_NE(err.find("out of range"), std::string::npos);
  EXPECT_DOUBLE_EQ(p.particleRadius, 0.01);  // unchanged after a rejected value

  const ParamInfo* iters = t.find("min_iterations");
  ASSERT_NE(iters, nullptr);
  EXPECT_NE(ParamTable::setScalar(p, *iters, 2.5), "");
  EXPECT_EQ(ParamTable::setScalar(p, *iters, 3), "");
  EXPECT_EQ(p.minIterations, 3);

  const ParamInfo* warm = t.find("warm_start");
  ASSERT_NE(warm, nullptr);
  EXPECT_EQ(ParamTable::setScalar(p, *warm, 0), "");
  EXPECT_FALSE(p.warmStart);

  const ParamInfo* g = t.find("gravity");
  ASSERT_NE(g, nullptr);
  EXPECT_EQ(ParamTable::setVec3(p, *g, {0, -1.62, 0}), "");
  EXPECT_DOUBLE_EQ(p.gravity[1], -1.62);
  EXPECT_NE(ParamTable::setVec3(p, *g, {0, -1000, 0}), "");
  EXPECT_NE(ParamTable::setScalar(p, *g, 1.0), "");
  EXPECT_EQ(t.find("no_such_parameter"), nullptr);
}

TEST(ParamTableTest, ValidatesRelations) {
  SimParams p;
  p.dtMin = 0.01;
  p.dtMax = 0.001;
  EXPECT_NE(ParamTable::validate(p).find("dt_min"), std::string::npos);
  p = SimParams{};
  p.minIterations = 50;
  p.maxIterations = 10;
  EXPECT_NE(ParamTable::validate(p).find("min_iterations"), std::string::npos);
}

// A default-constructed SimParams holds exactly the table's defaults, whatever the memory held before: the
// table is the one place a default is written.
TEST(ParamTableTest, DefaultsComeFromTheTable) {
  alignas(SimParams) unsigned char zeros[sizeof(SimParams)];
  alignas(SimParams) unsigned char ones[sizeof(SimParams)];
  std::memset(zeros, 0x00, sizeof(zeros));
  std::memset(ones, 0xff, sizeof(ones));
  const SimParams* a = new (zeros) SimParams();
  const SimParams* b = new (ones) SimParams();
  for (const ParamInfo& e : ParamTable::sim().entries()) {
    EXPECT_TRUE(ParamTable::equal(e, *a, *b)) << e.key;
    EXPECT_EQ(ParamTable::text(*a, e), ParamTable::defaultText(e)) << e.key;
  }
  EXPECT_TRUE(*a == *b);
  EXPECT_EQ(ParamTable::sim().at("particle_radius").key, "particle_radius");
  EXPECT_DOUBLE_EQ(SimParams().particleRadius,
                   std::get<double>(ParamTable::sim().at("particle_radius").defaultValue));

  // Every member of SimParams has an entry: the members the table reaches cover the struct but for padding
  // (a gap narrower than the 8-byte alignment). A member without an entry would leave a gap or, being
  // uninitialised, differ between the two buffers.
  std::map<std::size_t, std::size_t> covered;  // offset -> size
  for (const ParamInfo& e : ParamTable::sim().entries()) {
    const SimParams& p = *a;
    visit(e, p, [&](const auto& v) {
      if constexpr (!std::is_same_v<std::decay_t<decltype(v)>, Choice>) {
        const auto offset = std::size_t(reinterpret_cast<const unsigned char*>(&v) - zeros);
        EXPECT_TRUE(covered.emplace(offset, sizeof(v)).second) << e.key << " shares a member";
      }
    });
  }
  std::size_t end = 0;
  for (const auto& [offset, size] : covered) {
    EXPECT_LT(offset - end, 8u) << "a member at byte " << end << " has no table entry";
    EXPECT_EQ(std::memcmp(zeros + offset, ones + offset, size), 0);
    end = offset + size;
  }
  EXPECT_LT(sizeof(SimParams) - end, 8u) << "a member at byte " << end << " has no table entry";
  a->~SimParams();
  b->~SimParams();
}

// The visit hands each kind its own type.
TEST(ParamTableTest, VisitHandsTheMembersType) {
  SimParams p;
  std::map<ParamKind, std::set<std::string>> types;
  for (const ParamInfo& e : ParamTable::sim().entries()) {
    visit(e, p,
          Overloaded{[&](double&) { types[e.kind].insert("double"); },
                     [&](float&) { types[e.kind].insert("float"); },
                     [&](int&) { types[e.kind].insert("int"); }, [&](bool&) { types[e.kind].insert("bool"); },
                     [&](std::uint64_t&) { types[e.kind].insert("u64"); },
                     [&](std::array<double, 3>&) { types[e.kind].insert("vec3"); },
                     [&](Choice&) { types[e.kind].insert("choice"); }});
  }
  EXPECT_EQ(types[ParamKind::Number], std::set<std::string>{"double"});
  EXPECT_EQ(types[ParamKind::Integer], std::set<std::string>{"int"});
  EXPECT_EQ(types[ParamKind::Boolean], std::set<std::string>{"bool"});
  EXPECT_EQ(types[ParamKind::Vector3], std::set<std::string>{"vec3"});
  EXPECT_EQ(types[ParamKind::Seed], std::set<std::string>{"u64"});
  const ParamInfo& viscosity = ParamTable::sim().at("viscosity");
  visit(viscosity, p, [](auto& v) {
    if constexpr (std::is_same_v<std::decay_t<decltype(v)>, double>)
      v = 0.125;
  });
  EXPECT_EQ(p.viscosity, 0.125);
}

// "KEY=VALUE" as the command line's --set gives it, with the table's own one-line messages.
TEST(ParamTableTest, AssignsKeyValue) {
  const ParamTable& t = ParamTable::sim();
  SimParams p;
  EXPECT_EQ(t.assign(p, "dt_max=0.002"), "");
  EXPECT_EQ(p.dtMax, 0.002);
  EXPECT_EQ(t.assign(p, "gravity=0,-1.62,0"), "");
  EXPECT_EQ(p.gravity, (std::array<double, 3>{0, -1.62, 0}));
  EXPECT_EQ(t.assign(p, "gravity=[1, 2, 3]"), "");
  EXPECT_EQ(p.gravity, (std::array<double, 3>{1, 2, 3}));
  EXPECT_EQ(t.assign(p, "warm_start=off"), "");
  EXPECT_FALSE(p.warmStart);
  EXPECT_EQ(t.assign(p, "warm_start=true"), "");
  EXPECT_TRUE(p.warmStart);
  EXPECT_EQ(t.assign(p, "seed=4294967295"), "");
  EXPECT_EQ(p.seed, 4294967295u);
  EXPECT_EQ(t.assign(p, "min_iterations=5"), "");
  EXPECT_EQ(p.minIterations, 5);

  const SimParams before = p;
  EXPECT_EQ(t.assign(p, "dt_mx=0.002"), "unknown parameter 'dt_mx' (did you mean dt_max?)");
  EXPECT_EQ(t.assign(p, "zzzzzz=1"), "unknown parameter 'zzzzzz'");
  EXPECT_EQ(t.assign(p, "dt_max"), "expected KEY=VALUE, got 'dt_max'");
  EXPECT_EQ(t.assign(p, "=3"), "expected KEY=VALUE, got '=3'");
  EXPECT_EQ(t.assign(p, "dt_max=fast"), "dt_max: expected a number, got 'fast'");
  EXPECT_EQ(t.assign(p, "dt_max=0.002x"), "dt_max: expected a number, got '0.002x'");
  EXPECT_EQ(t.assign(p, "dt_max=1"), "dt_max = 1 is out of range [1e-05, 0.05]");
  EXPECT_EQ(t.assign(p, "min_iterations=2.5"), "min_iterations must be an integer");
  EXPECT_EQ(t.assign(p, "min_iterations=many"), "min_iterations: expected an integer, got 'many'");
  EXPECT_EQ(t.assign(p, "warm_start=2"), "warm_start: expected true or false, got '2'");
  EXPECT_EQ(t.assign(p, "gravity=0,1"), "gravity: expected three numbers x,y,z, got '0,1'");
  EXPECT_EQ(t.assign(p, "gravity=0,1000,0"), "gravity has a component out of range [-100, 100]");
  EXPECT_EQ(t.assign(p, "seed=-1"), "seed = -1 is out of range [0, 4.29497e+09]");
  EXPECT_EQ(t.assign(p, "viscosity=nan"), "viscosity must be a finite number");
  EXPECT_TRUE(p == before);  // a rejected assignment changes nothing

  // relations are checked once every assignment is in, so their order does not matter
  SimParams q;
  EXPECT_EQ(t.assignAll(q, {"dt_min=0.008", "dt_max=0.01"}), "");
  EXPECT_EQ(q.dtMin, 0.008);
  EXPECT_EQ(t.assignAll(q, {"dt_min=0.01", "dt_max=0.001"}), "dt_min must not exceed dt_max");
  EXPECT_EQ(t.assignAll(q, {"dt_max=0.01", "bogus=1"}), "unknown parameter 'bogus'");
  EXPECT_EQ(t.assignAll(q, {"merge_receivers_below=0.5"}),
            "the thresholds must keep merge_below < merge_receivers_below <= 1");
  EXPECT_EQ(t.assignAll(q, {"merge_receivers_below=0.9"}), "");

  // ranges for options that take them from the table
  EXPECT_EQ(t.at("seed").min, 0.0);
  EXPECT_EQ(t.at("seed").max, 4294967295.0);
  EXPECT_THROW(t.at("sed"), std::out_of_range);
}

// Every parameter's text form reads back to the same value, and the help lists each key once.
TEST(ParamTableTest, TextRoundTrips) {
  const ParamTable& t = ParamTable::sim();
  SimParams p;
  p.gravity = {0.1, -9.80665, 1.0 / 3.0};
  p.dtMin = 1.0 / 7.0 * 1e-4;
  p.seed = 123456789;
  p.divergenceSolve = false;
  for (const ParamInfo& e : t.entries()) {
    SimParams q;
    EXPECT_EQ(ParamTable::setText(q, e, ParamTable::text(p, e)), "") << e.key;
    EXPECT_TRUE(ParamTable::equal(e, p, q)) << e.key << " " << ParamTable::text(p, e);
  }
  const std::vector<std::string> help = t.helpLines();
  ASSERT_EQ(help.size(), t.entries().size());
  EXPECT_EQ(help[0].rfind("particle_radius: ", 0), 0u) << help[0];
  EXPECT_NE(help[0].find("default 0.025"), std::string::npos) << help[0];
}
