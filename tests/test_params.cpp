// The parameter table: unique keys, defaults in range, validation of values and relations.
#include <gtest/gtest.h>

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
