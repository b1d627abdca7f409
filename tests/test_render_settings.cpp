// The render settings table: one declaration per setting (defaults come from the table), KEY=VALUE for the
// command line, choices by name, and the strict reader reading it like the simulation's table.
#include <gtest/gtest.h>

#include <cstring>
#include <new>
#include <set>

#include "engine/json_reader.h"
#include "render/render_settings.h"

namespace fp::render {
namespace {

TEST(RenderSettingsTableTest, DefaultsComeFromTheTable) {
  alignas(RenderSettings) unsigned char zeros[sizeof(RenderSettings)];
  alignas(RenderSettings) unsigned char ones[sizeof(RenderSettings)];
  std::memset(zeros, 0x00, sizeof(zeros));
  std::memset(ones, 0xff, sizeof(ones));
  const RenderSettings* a = new (zeros) RenderSettings();
  const RenderSettings* b = new (ones) RenderSettings();
  const RenderSettingsTable& t = RenderSettingsTable::get();
  std::set<std::string> keys;
  for (const auto& e : t.entries()) {
    EXPECT_TRUE(keys.insert(e.key).second) << e.key;
    EXPECT_FALSE(e.description.empty()) << e.key;
    EXPECT_TRUE(RenderSettingsTable::equal(e, *a, *b)) << e.key;
    EXPECT_EQ(RenderSettingsTable::text(*a, e), RenderSettingsTable::defaultText(e)) << e.key;
    const double v = RenderSettingsTable::getScalar(*a, e);
    EXPECT_GE(v, e.min) << e.key;
    EXPECT_LE(v, e.max) << e.key;
  }
  EXPECT_TRUE(t.allEqual(*a, *b));
  EXPECT_EQ(a->view, RenderSettings::View::Fluid);
  EXPECT_EQ(a->colorField, ColorField::Nu);
  EXPECT_EQ(a->highlightDuration, 0.5f);
  EXPECT_GE(keys.size(), 10u);
  a->~RenderSettings();
  b->~RenderSettings();
}

TEST(RenderSettingsTableTest, AssignsKeyValue) {
  const RenderSettingsTable& t = RenderSettingsTable::get();
  RenderSettings s;
  EXPECT_EQ(t.assignAll(s, {"view=particles", "color_field=density-error", "highlight_duration=1.5",
                            "show_spray=off", "filter_iterations=4"}),
            "");
  EXPECT_EQ(s.view, RenderSettings::View::Particles);
  EXPECT_EQ(s.colorField, ColorField::DensityError);
  EXPECT_EQ(s.highlightDuration, 1.5f);
  EXPECT_FALSE(s.showSpray);
  EXPECT_EQ(s.filterIterations, 4);
  // every choice name is the one the rest of the program uses
  for (ColorField f : {ColorField::MassLevel, ColorField::Phi, ColorField::Omega, ColorField::Nu,
                       ColorField::Speed, ColorField::DensityError}) {
    EXPECT_EQ(t.assign(s, std::string("color_field=") + colorFieldName(f)), "");
    EXPECT_EQ(s.colorField, f);
  }
  EXPECT_EQ(t.assign(s, "veiw=fluid"), "unknown render setting 'veiw' (did you mean view?)");
  EXPECT_EQ(t.assign(s, "view=water"), "view: expected fluid or particles, got 'water'");
  EXPECT_EQ(t.assign(s, "color_field=omgea"),
            "color_field: expected mass, phi, omega, nu, speed or density-error, got 'omgea' (did you mean "
            "omega?)");
  EXPECT_EQ(t.assign(s, "highlight_duration=0"), "highlight_duration = 0 is out of range [0.01, 10]");
  EXPECT_EQ(t.assign(s, "filter_iterations=1.5"), "filter_iterations must be an integer");
}

TEST(RenderSettingsTableTest, JsonRoundTrip) {
  RenderSettings s;
  s.view = RenderSettings::View::Particles;
  s.colorField = ColorField::Omega;
  s.refraction = 0.125f;
  const nlohmann::ordered_json j = engine::tableToJson(RenderSettingsTable::get(), s);
  EXPECT_EQ(j["view"], "particles");
  EXPECT_EQ(j["color_field"], "omega");
  const engine::JsonReader reader("r.json");
  RenderSettings q;
  reader.readTable(reader.parse(j.dump()), "$", RenderSettingsTable::get(), q);
  EXPECT_TRUE(RenderSettingsTable::get().allEqual(s, q));
  try {
    reader.readTable(reader.parse(R"({"view": 1})"), "$", RenderSettingsTable::get(), q);
    ADD_FAILURE();
  } catch (const sim::InputError& e) {
    EXPECT_STREQ(e.what(), "r.json: $.view: expected a string, got a number");
  }
}

}  // namespace
}  // namespace fp::render
