// fovea catalog: the scene catalog at a glance; fovea textures: the texture
// kinds as PNG files.
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "output.h"
#include "scene_options.h"
#include "scenes/catalog.h"
#include "scenes/textures.h"

namespace experiments {
namespace {

struct CatalogArgs {
  std::string out;
  int thumb_width = 320;
};

void Label(cv::Mat& image, const std::string& text) {
  cv::rectangle(image, {0, 0, image.cols, 22}, cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(image, text, {6, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 1,
              cv::LINE_AA);
}

int Catalog(const CatalogArgs& args) {
  std::vector<cv::Mat> rows;
  for (const std::string& name : scenes::CatalogNames()) {
    SceneOptions options;
    options.scene = name;
    auto sim = options.Load();
    const rig::StereoFrame frame = sim->rig().Capture({/*color=*/true});
    const sim::TrueView truth = sim->truth().Render(frame.left.world_T_camera, frame.left.intrinsics);
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
  EnsureDirectory(args.out);
  WriteImageAtomic(args.out + "/contact_sheet.png", sheet);
  std::printf("%s/contact_sheet.png\n", args.out.c_str());
  return 0;
}

struct TexturesArgs {
  std::string out;
  uint64_t seed = 1;
};

int Textures(const TexturesArgs& args) {
  EnsureDirectory(args.out);
  for (const std::string& kind : scenes::TextureKinds()) {
    const std::string path = args.out + "/" + kind + "-s" + std::to_string(args.seed) + ".png";
    WriteImageAtomic(path, scenes::MakeTexture(kind, args.seed));
    std::printf("%s\n", path.c_str());
  }
  return 0;
}

}  // namespace

void AddCatalogCommands(CLI::App& app, std::function<int()>* run) {
  auto cat = std::make_shared<CatalogArgs>();
  CLI::App* c = app.add_subcommand(
      "catalog", "render every catalog scene at the home pose into one contact sheet PNG");
  c->add_option("--out", cat->out, "output folder")->required();
  c->add_option("--width", cat->thumb_width, "thumbnail width in pixels")->check(CLI::Range(64, 1280));
  c->callback([cat, run] { *run = [cat] { return Catalog(*cat); }; });

  auto tex = std::make_shared<TexturesArgs>();
  CLI::App* t = app.add_subcommand(
      "textures", "write every procedural texture kind as <kind>-s<seed>.png");
  t->add_option("--out", tex->out, "output folder")->required();
  t->add_option("--seed", tex->seed, "texture seed");
  t->callback([tex, run] { *run = [tex] { return Textures(*tex); }; });
}

}  // namespace experiments
