// The run configuration (experiments/config/config.h): one number parser,
// YAML read strictly, and a dump that reads back to itself.
#include "experiments/config/config.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "experiments/output/output.h"

TEST_CASE("numbers: finite decimal text and nothing else", "[config]") {
  using experiments::ParseNumber;
  CHECK(ParseNumber("3") == 3.0);
  CHECK(ParseNumber("-0.5") == -0.5);
  CHECK(ParseNumber("2e-3") == 0.002);
  for (const char* bad :
       {"", " 1", "1 ", "1x", "nan", "NaN", "inf", "-inf", "1e999", "0x10", "+", "--1", "1,5"})
    CHECK_FALSE(ParseNumber(bad));
}

TEST_CASE("parameters: whole numbers are exact, ranges hold, messages name the key or the flag",
          "[config]") {
  experiments::RunConfig c;
  CHECK_NOTHROW(experiments::SetParam(&c, "seed", "9007199254740992"));
  CHECK(c.seed == 9007199254740992ull);
  CHECK_THROWS_WITH(experiments::SetParam(&c, "seed", "9007199254740993"),
                    Catch::Contains("out of range"));
  CHECK_THROWS_WITH(experiments::SetParam(&c, "seed", "-1"),
                    Catch::Contains("key 'seed': -1 is out of range"));
  CHECK_THROWS_WITH(experiments::SetParam(&c, "loop.fixations", "2.5"),
                    Catch::Contains("expected a whole number"));
  CHECK_THROWS_WITH(experiments::SetParamFromFlag(&c, "--sigma", "idr.log_sigma_px", "0"),
                    Catch::Equals("--sigma (idr.log_sigma_px): 0 is out of range [1, 8]"));
  CHECK_THROWS_WITH(experiments::SetParam(&c, std::string(5000, 'k'), "1"),
                    Catch::Contains("characters)") && !Catch::Contains(std::string(300, 'k')));
}

TEST_CASE("YAML: repeated keys, several documents and non-mappings are refused", "[config]") {
  using experiments::ParseYaml;
  CHECK_THROWS_WITH(ParseYaml("loop:\n  fixations: 3\nloop:\n  fixations: 4\n", ""),
                    Catch::Contains("'loop' appears twice"));
  CHECK_THROWS_WITH(ParseYaml("a: {b: 1, b: 2}\n", ""), Catch::Contains("'b' appears twice"));
  CHECK_THROWS_WITH(ParseYaml("seed: 1\n---\nseed: 2\n", ""),
                    Catch::Contains("more than one YAML document"));
  CHECK_THROWS_WITH(ParseYaml("{[1]: 2}\n", ""), Catch::Contains("not a single value"));
  CHECK_THROWS_WITH(ParseYaml(",", ""),
                    Catch::Contains("not valid YAML"));  // yaml-cpp's LoadAll never returns
  CHECK_NOTHROW(ParseYaml("", ""));
  CHECK_NOTHROW(ParseYaml("---\nseed: 3\n...\n", ""));
  experiments::RunConfig c;
  CHECK_THROWS_WITH(experiments::ApplyYaml(ParseYaml("[1, 2]\n", ""), &c, ""),
                    Catch::Contains("mapping"));
}

TEST_CASE("the dumped configuration reads back to the same dump and the same run id", "[config]") {
  experiments::RunConfig c;
  for (const auto& [key, value] :
       std::vector<std::pair<std::string, std::string>>{{"rig.port", "/dev/tty #1"},
                                                        {"rig.left_camera", "a: b"},
                                                        {"rig.right_camera", "x\ny\t\"z'"},
                                                        {"rig.calibration", "null"},
                                                        {"scene", "  spaced  "},
                                                        {"seed", "9007199254740992"}})
    experiments::SetParam(&c, key, value);
  const std::string dump = experiments::DumpConfig(c);
  experiments::RunConfig back;
  experiments::ApplyYaml(experiments::ParseYaml(dump, ""), &back, "");
  CHECK(experiments::DumpConfig(back) == dump);
  CHECK(back.hardware.port == "/dev/tty #1");
  CHECK(back.hardware.right_camera == "x\ny\t\"z'");
  CHECK(back.scene == "  spaced  ");
  CHECK(experiments::ConfigHash(back) == experiments::ConfigHash(c));
}

TEST_CASE("string parameters hold UTF-8 text without control characters", "[config]") {
  experiments::RunConfig c;
  CHECK_NOTHROW(
      experiments::SetParam(&c, "rig.port", "/dev/tty\xc3\xa9 \xe2\x82\xac \xf0\x9f\x93\xb7\t\n"));
  for (const char* bad : {"a\x01", "a\x7f", "\x96", "\xc3", "\xc0\xaf", "\xed\xa0\x80",
                          "\xf4\x90\x80\x80", "\xc2\x85"})
    CHECK_THROWS_WITH(experiments::SetParam(&c, "rig.port", bad), Catch::Contains("UTF-8 text"));
}

namespace {

// What a parameter at an extreme needs from the others to be a valid
// configuration (the couplings RunConfig::Check states): none for most.
void Couple(const std::string& key, double value, experiments::RunConfig* c) {
  using experiments::SetParam;
  if ((key == "rig.home_baseline_m" || key == "static.baseline_m") && value > 0.6)
    SetParam(c, "rig.carriage_max_m", "2");
  if (key == "rig.carriage_max_m" && value < 0.05) {
    SetParam(c, "rig.home_baseline_m", "0.01");
    SetParam(c, "foveal.baseline_m", "0.01");
    SetParam(c, "foveal.mapped_baseline_m", "0.01");
  }
  if (key == "idr.min_expansion" && value > 4) SetParam(c, "idr.max_expansion", "16");
}

}  // namespace

TEST_CASE("every parameter of the table: both ends pass, just outside is refused naming the key",
          "[config]") {
  experiments::RunConfig table_owner;
  int numbers = 0, flags = 0, choices = 0;
  for (const experiments::ConfigParam& p : experiments::ConfigParams(&table_owner)) {
    const std::string key = p.path();
    INFO(key);
    const rig::ParamSpec& spec = *p.spec;
    auto accepted = [&](const std::string& text, double value) {
      experiments::RunConfig c;
      Couple(key, value, &c);
      experiments::SetParam(&c, key, text);
      c.Check();  // the libraries' Check() against the same specs
    };
    auto refused = [&](const std::string& text) {
      experiments::RunConfig c;
      CHECK_THROWS_WITH(experiments::SetParam(&c, key, text), Catch::Contains("key '" + key + "'"));
    };
    if (std::holds_alternative<bool*>(p.target)) {
      ++flags;
      CHECK_NOTHROW(accepted("true", 0));
      CHECK_NOTHROW(accepted("false", 0));
      refused("maybe");
    } else if (std::holds_alternative<std::string*>(p.target)) {
      if (!spec.choices) continue;  // any text (rig.units and rig.directions: their own parser)
      ++choices;
      for (const char* const* c = spec.choices; *c; ++c)
        if (std::string(*c) != "hardware") CHECK_NOTHROW(accepted(*c, 0));
      refused("nope");
    } else {
      ++numbers;
      const bool whole = !std::holds_alternative<double*>(p.target);
      CHECK_NOTHROW(accepted(rig::FormatParamNumber(spec.lo), spec.lo));
      CHECK_NOTHROW(accepted(rig::FormatParamNumber(spec.hi), spec.hi));
      // Whole numbers one past each end, written as digits (exact past
      // 2^53); others the next double outside.
      auto digits = [](double v) { return std::to_string(static_cast<long long>(v)); };
      refused(whole ? digits(spec.lo - 1)
                    : rig::FormatParamNumber(std::nextafter(spec.lo, -1e300)));
      refused(whole ? std::to_string(static_cast<long long>(spec.hi) + 1)
                    : rig::FormatParamNumber(std::nextafter(spec.hi, 1e300)));
      refused("nan");
    }
  }
  CHECK(numbers > 70);
  CHECK(flags > 10);
  // method, matcher, rig type, nl1.cost, selection strategy, first fixation,
  // view and reference fallback
  CHECK(choices == 8);
}

TEST_CASE("the options' own Check() names the YAML key and uses the table's range", "[config]") {
  fovea::ServoOptions servo;
  servo.max_steps = 0;
  CHECK_THROWS_WITH(servo.Check(),
                    Catch::Equals("key 'foveal.servo_max_steps': 0 is out of range [1, 50]"));
  experiments::RunConfig c;
  CHECK_THROWS_WITH(experiments::SetParam(&c, "foveal.servo_max_steps", "0"),
                    Catch::Equals("key 'foveal.servo_max_steps': 0 is out of range [1, 50]"));
  fovea::IdrOptions idr;
  idr.unique_share = 0.3;
  CHECK_THROWS_WITH(idr.Check(),
                    Catch::Equals("key 'idr.unique_share': 0.3 is out of range [0.5, 1]"));
  sim::SimRigConfig rig;
  rig.width_px = 32;
  CHECK_THROWS_WITH(rig.Check(),
                    Catch::Equals("key 'rig.width_px': 32 is out of range [64, 4096]"));
}
