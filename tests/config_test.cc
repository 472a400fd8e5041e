// The run configuration (experiments/src/config.h): one number parser,
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
