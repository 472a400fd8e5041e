// fovea catalog: the scene catalog at a glance; fovea textures: the texture
// kinds as PNG files.
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "experiments/output/output.h"
#include "scene_options.h"
#include "scenes/catalog.h"
#include "scenes/textures.h"

namespace experiments {
namespace {

struct CatalogArgs {
  std::string out;
  int thumb_width = 320;
  bool force = false;
};

void Label(cv::Mat& image, const std::string& text) {
  cv::rectangle(image, {0, 0, image.cols, 22}, cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(image, text, {6, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 1,
              cv::LINE_AA);
}

int Catalog(const CatalogArgs& args) {
  // One file into a folder that may hold others (the README's figures).
  const std::string sheet_path = CheckOutputFile(
      NormalizeOutputPath(args.out, "--out") + "/contact_sheet.png", "--out", args.force);
  std::vector<cv::Mat> rows;
  for (const std::string& name : scenes::CatalogNames()) {
    RunConfig config;
    config.rig.noise.read_noise_sigma_dn = 0;
    config.scene = name;
    auto sim = LoadSceneOf(config);
    const rig::StereoFrame frame = sim->rig().Capture({/*color=*/true});
    const sim::TrueView truth =
        sim->truth().Render(frame.left.world_T_camera, frame.left.intrinsics);
    cv::Mat left, right, depth;
    const double scale = double(args.thumb_width) / frame.left.bgr.cols;
    cv::resize(frame.left.bgr, left, {}, scale, scale, cv::INTER_AREA);
    cv::resize(frame.right.bgr, right, {}, scale, scale, cv::INTER_AREA);
    cv::resize(ColorizeDepth(truth.depth_m), depth, {}, scale, scale, cv::INTER_NEAREST);
    double lo = 0, hi = 0;
    cv::minMaxLoc(truth.depth_m, &lo, &hi, nullptr, nullptr, truth.depth_m > 0);
    Label(left, name + ": left");
    Label(right, "right");
    char range[64];
    std::snprintf(range, sizeof range, "true depth %.2f-%.2f m", lo, hi);
    Label(depth, range);
    cv::Mat row;
    cv::hconcat(std::vector<cv::Mat>{left, right, depth}, row);
    rows.push_back(row);
    std::fprintf(stderr, "fovea catalog: %s\n", name.c_str());
  }
  cv::Mat sheet;
  cv::vconcat(rows, sheet);
  EnsureDirectory(std::filesystem::path(sheet_path).parent_path().string());
  WriteImageAtomic(sheet_path, sheet);
  std::printf("%s\n", sheet_path.c_str());
  return 0;
}

struct TexturesArgs {
  std::string out;
  std::string seed = "1";
  bool force = false;
};

int Textures(const TexturesArgs& args) {
  const uint64_t seed = static_cast<uint64_t>(*ParseNumber(args.seed));
  OutputFolder folder(args.out, "--out", ExistingPolicy(args.force));
  std::vector<std::string> names;
  for (const std::string& kind : scenes::TextureKinds()) {
    names.push_back(kind + "-s" + std::to_string(seed) + ".png");
    WriteImageAtomic(folder.path() + "/" + names.back(), scenes::MakeTexture(kind, seed));
  }
  folder.Commit();
  for (const std::string& name : names)
    std::printf("%s/%s\n", folder.target().c_str(), name.c_str());
  return 0;
}

}  // namespace

void AddCatalogCommands(CLI::App& app, std::function<int()>* run) {
  auto cat = std::make_shared<CatalogArgs>();
  CLI::App* c = app.add_subcommand(
      "catalog", "render every catalog scene at the home pose into one contact sheet PNG");
  c->add_option("--out", cat->out,
                "folder to write contact_sheet.png into (it may hold other files)")
      ->required();
  c->add_option("--width", cat->thumb_width, "thumbnail width in pixels")
      ->check(CLI::Range(64, 1280));
  c->add_flag("--force", cat->force, "replace an existing contact_sheet.png there");
  c->callback([cat, run] { *run = [cat] { return Catalog(*cat); }; });

  auto tex = std::make_shared<TexturesArgs>();
  CLI::App* t =
      app.add_subcommand("textures", "write every procedural texture kind as <kind>-s<seed>.png");
  t->add_option("--out", tex->out, "output folder (new, or empty)")->required();
  AddForceFlag(t, &tex->force);
  t->add_option("--seed", tex->seed, "texture seed")
      ->check(NumberIn(0, 9007199254740992.0, /*whole=*/true));
  t->callback([tex, run] { *run = [tex] { return Textures(*tex); }; });
}

}  // namespace experiments
