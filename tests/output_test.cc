// The output-folder policy (experiments/src/output.h): a target is new or
// empty, or replaced only when fovea wrote it and --force says so; results
// appear whole under the target's name or not at all; nothing else is
// touched.
#include "experiments/output/output.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace {

fs::path FreshDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("fovea_output_test_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string Read(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

TEST_CASE("output paths are normalized, and the folders above refused", "[output]") {
  using experiments::NormalizeOutputPath;
  CHECK(NormalizeOutputPath("out/run/", "--out") == "out/run");
  CHECK(NormalizeOutputPath("out//run/./", "--out") == "out/run");
  CHECK(NormalizeOutputPath("/tmp/x/../y", "--out") == "/tmp/y");
  for (const char* bad : {"", ".", "./", "..", "../", "/", "out/.."})
    CHECK_THROWS_AS(NormalizeOutputPath(bad, "--out"), experiments::UsageError);
  CHECK_THROWS_WITH(NormalizeOutputPath(std::string(300, 'x'), "--out"),
                    Catch::Contains("too long"));
}

TEST_CASE("an output folder appears whole on Commit, and nothing without it", "[output]") {
  const fs::path dir = FreshDir("commit");
  const fs::path target = dir / "a" / "b" / "run";
  {
    experiments::OutputFolder out(target.string(), "--out", experiments::ExistingOutput::kRefuse);
    CHECK_FALSE(fs::exists(dir / "a"));  // nothing until the first path()
    std::ofstream(out.path() + "/half.txt") << "half";
    CHECK_FALSE(fs::exists(target));
  }  // dropped without Commit: the staging folder and the parents it made are gone
  CHECK(fs::is_empty(dir));
  {
    experiments::OutputFolder out(target.string(), "--out", experiments::ExistingOutput::kRefuse);
    std::ofstream(out.path() + "/result.txt") << "whole";
    out.Commit();
  }
  CHECK(Read(target / "result.txt") == "whole");
  CHECK(fs::exists(target / experiments::kOutputMarker));
  for (const auto& e : fs::directory_iterator(target.parent_path()))
    CHECK(e.path().filename().string().find("partial") == std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("existing targets: refused, or replaced with --force only when fovea wrote them",
          "[output]") {
  const fs::path dir = FreshDir("existing");
  using experiments::ExistingOutput;
  using experiments::OutputFolder;
  fs::create_directories(dir / "theirs");
  std::ofstream(dir / "theirs" / "notes.txt") << "theirs";
  std::ofstream(dir / "file.txt") << "a file";
  fs::create_directories(dir / "empty");
  fs::create_directory_symlink(dir / "empty", dir / "link");
  CHECK_THROWS_WITH(OutputFolder((dir / "theirs").string(), "--out", ExistingOutput::kRefuse),
                    Catch::Contains("exists and is not empty"));
  CHECK_THROWS_WITH(OutputFolder((dir / "theirs").string(), "--out", ExistingOutput::kReplace),
                    Catch::Contains("was not written by fovea"));
  CHECK_THROWS_WITH(OutputFolder((dir / "file.txt").string(), "--out", ExistingOutput::kReplace),
                    Catch::Contains("is not a folder"));
  CHECK_THROWS_WITH(OutputFolder((dir / "link").string(), "--out", ExistingOutput::kReplace),
                    Catch::Contains("symbolic link"));
  CHECK(Read(dir / "theirs" / "notes.txt") == "theirs");
  {  // an empty folder is fine
    OutputFolder out((dir / "empty").string(), "--out", ExistingOutput::kRefuse);
    std::ofstream(out.path() + "/v1.txt") << "1";
    out.Commit();
  }
  CHECK_THROWS(OutputFolder((dir / "empty").string(), "--out", ExistingOutput::kRefuse));
  {  // fovea's own folder, with --force: replaced whole
    OutputFolder out((dir / "empty").string(), "--out", ExistingOutput::kReplace);
    std::ofstream(out.path() + "/v2.txt") << "2";
    out.Commit();
  }
  CHECK(fs::exists(dir / "empty" / "v2.txt"));
  CHECK_FALSE(fs::exists(dir / "empty" / "v1.txt"));
  CHECK(Read(dir / "file.txt") == "a file");
  fs::remove_all(dir);
}

TEST_CASE("staging folders of processes that are gone are removed, live ones kept", "[output]") {
  const fs::path dir = FreshDir("stale");
  const std::string target = (dir / "run").string();
  const std::string mine = experiments::StagingPath(target);
  const std::string prefix = mine.substr(0, mine.rfind('-') + 1);
  // A pid above pid_max is never alive; our parent is.
  const std::string dead = prefix + "999999999", alive = prefix + std::to_string(getppid());
  const std::string other_host = (dir / ".run.partial-otherhost-999999999").string();
  for (const std::string& p : {dead, alive, other_host}) fs::create_directories(p);
  experiments::RemoveStaleStaging(target);
  CHECK_FALSE(fs::exists(dead));
  CHECK(fs::exists(alive));
  CHECK(fs::exists(other_host));  // another machine's process may still be writing it
  fs::remove_all(dir);
}

TEST_CASE("a one-file output refuses what exists unless --force, and never a folder", "[output]") {
  const fs::path dir = FreshDir("file");
  std::ofstream(dir / "calibration.yaml") << "old";
  CHECK(experiments::CheckOutputFile((dir / "new.yaml").string(), "--out", false) ==
        (dir / "new.yaml").string());
  CHECK_THROWS_WITH(
      experiments::CheckOutputFile((dir / "calibration.yaml").string(), "--out", false),
      Catch::Contains("pass --force"));
  CHECK_NOTHROW(experiments::CheckOutputFile((dir / "calibration.yaml").string(), "--out", true));
  CHECK_THROWS_WITH(experiments::CheckOutputFile(dir.string(), "--out", true),
                    Catch::Contains("not a file"));
  fs::remove_all(dir);
}
