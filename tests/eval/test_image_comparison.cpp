// Image comparisons: the crop goes where the upscalers' errors differ most from bicubic's, the
// same every time; every error map of a frame shares one colour scale; `cgsr eval
// --save-images` writes the pictures and a page whose links all resolve, and the page opens in
// headless Chromium without a console error (when Chromium is installed).
#include <gtest/gtest.h>

#include <cstdlib>
#include <opencv2/imgcodecs.hpp>

#include "core/atomic_file.h"
#include "eval/image_comparison.h"
#include "models/model_file.h"
#include "tests/support/cli_runner.h"
#include "tests/support/page_links.h"
#include "tests/support/tiny_data.h"

using namespace cgsr;
using namespace cgsr::test;
namespace fs = std::filesystem;
using torch::indexing::Slice;

namespace {
torch::Tensor image(int64_t h, int64_t w, int seed) {
  torch::manual_seed(seed);
  return torch::rand({1, 3, h, w});
}
}  // namespace

TEST(ImageComparison, CropGoesWhereErrorsDifferFromBicubicAndIsDeterministic) {
  const auto truth = image(96, 128, 1);
  const auto bicubic = truth + 0.05;
  auto better = bicubic.clone();
  better.index_put_({Slice(), Slice(), Slice(40, 72), Slice(80, 112)}, truth.index({Slice(), Slice(), Slice(40, 72), Slice(80, 112)}));
  const cv::Point at = choose_crop({better}, bicubic, truth, 32);
  EXPECT_EQ(at, cv::Point(80, 40));
  EXPECT_EQ(choose_crop({better}, bicubic, truth, 32), at);
  // Nothing differs: the first window in row order.
  EXPECT_EQ(choose_crop({bicubic.clone()}, bicubic, truth, 32), cv::Point(0, 0));
  // A crop larger than the frame starts at the corner.
  EXPECT_EQ(choose_crop({better}, bicubic, truth, 200), cv::Point(0, 0));
}

TEST(ImageComparison, ErrorMapsShareOneScale) {
  const auto truth = torch::full({1, 3, 16, 16}, 0.5);
  const auto small = truth + 0.02, large = truth + 0.2;
  const cv::Rect all(0, 0, 16, 16);
  const double scale = shared_error_scale({small, large}, truth, all);
  EXPECT_NEAR(scale, 0.2, 1e-5);  // the larger error sets it for both
  EXPECT_NEAR(shared_error_scale({small}, truth, all), 0.02, 1e-5);
  EXPECT_NEAR(shared_error_scale({truth.clone()}, truth, all), 1.0 / 255.0, 1e-9);  // never zero
  // The same error is the same colour in every map; the top of the scale is the colour bar's end.
  const cv::Mat a = error_map(large, truth, all, scale), b = error_map(large.clone(), truth, all, scale);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0);
  const cv::Mat dark = error_map(small, truth, all, scale);
  EXPECT_LT(cv::norm(dark.at<cv::Vec3b>(0, 0)), cv::norm(a.at<cv::Vec3b>(0, 0)));
}

TEST(ImageComparison, FramesWithTheMostEdgesComeFirst) {
  EvalResult r;
  for (auto [frame, edges] : std::vector<std::pair<int, double>>{{3, 0.01}, {4, 0.05}, {5, 0.02}, {6, 0.05}}) {
    FrameScore f;
    f.frame = frame;
    f.edge_fraction = edges;
    r.frames.push_back(f);
  }
  EXPECT_EQ(frames_with_most_edges(r, 3), (std::vector<int>{4, 6, 5}));
  EXPECT_EQ(frames_with_most_edges(r, 10).size(), 4u);
}

TEST(ImageComparison, EvalSaveImagesWritesPicturesAndAPageWhoseLinksResolve) {
  const auto dir = scratch_dir("image-comparison");
  save_model(dir / "pan.cgsr", *SRNetwork(default_spec("pan", 2)));
  const std::string args = "eval --data " + tiny_data().string() + " --model bicubic --model " +
                           (dir / "pan.cgsr").string() + " --split all --latency-runs 0 --save-images 2 --threads 1";
  const auto first = run_cgsr(args + " --out " + (dir / "a").string());
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const auto second = run_cgsr(args + " --out " + (dir / "b").string());
  ASSERT_EQ(second.exit_code, 0) << second.err;

  const auto results = read_json(dir / "a" / "results.json");
  ASSERT_EQ(results["comparisons"].size(), 2u);
  for (const auto& c : results["comparisons"]) {
    const auto region = c["region"].get<std::vector<int>>();
    EXPECT_GE(region[0], 0);
    EXPECT_LE(region[0] + region[2], 128);  // the tiny scene's HR frames are 128x96
    EXPECT_LE(region[1] + region[3], 96);
    for (const char* key : {"crops", "errors"}) {
      const cv::Mat png = cv::imread((dir / "a" / "images" / c[key].get<std::string>()).string());
      EXPECT_FALSE(png.empty()) << c[key];
    }
    EXPECT_EQ(c["crop_psnr"].size(), 4u);  // nearest, bicubic, fsr, the network
  }
  // The same frames and regions, byte for byte the same pictures.
  EXPECT_EQ(results["comparisons"], read_json(dir / "b" / "results.json")["comparisons"]);
  const std::string crops = results["comparisons"][0]["crops"];
  EXPECT_EQ(read_file(dir / "a" / "images" / crops), read_file(dir / "b" / "images" / crops));

  const auto page = dir / "a" / "index.html";
  ASSERT_TRUE(fs::exists(page));
  EXPECT_EQ(page_links(page).size(), 5u);  // two crop grids, two error maps and PSNR per frame
  EXPECT_TRUE(missing_links(page).empty()) << missing_links(page).front();
}

// The page in a real browser: no console error (a script error, or a picture that does not
// load), and a screenshot that shows something.
TEST(ImageComparison, PageOpensInHeadlessChromiumWithoutConsoleErrors) {
  if (std::system("command -v chromium > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "chromium is not installed (scripts/install-deps.sh --with-optional installs it)";
  const auto dir = scratch_dir("report-page-browser");
  const auto eval = run_cgsr("eval --data " + tiny_data().string() +
                             " --model classic --split all --latency-runs 0 --save-images 1 --threads 1 --out " +
                             (dir / "eval").string());
  ASSERT_EQ(eval.exit_code, 0) << eval.err;
  // A page with a broken picture must be caught too: the same page, one link pointing nowhere.
  std::string html = slurp(dir / "eval" / "index.html");
  const auto at = html.find("images/");
  ASSERT_NE(at, std::string::npos);
  write_file_atomic(dir / "eval" / "broken.html", html.replace(at, 7, "missing/"));

  const auto open = [&](const std::string& page, const fs::path& shot) {
    const std::string command = "timeout 120 chromium --headless --no-sandbox --disable-gpu --hide-scrollbars "
                                "--enable-logging=stderr --v=0 --window-size=1280,900 --screenshot=" + shot.string() +
                                " file://" + (dir / "eval" / page).string() + " 2> " + (dir / "chromium.err").string();
    EXPECT_EQ(std::system(command.c_str()), 0) << slurp(dir / "chromium.err");
    return slurp(dir / "chromium.err");
  };
  const std::string log = open("index.html", dir / "page.png");
  EXPECT_EQ(log.find("CONSOLE"), std::string::npos) << log;
  const cv::Mat shot = cv::imread((dir / "page.png").string());
  ASSERT_FALSE(shot.empty());
  EXPECT_EQ(shot.cols, 1280);
  cv::Scalar mean, stddev;
  cv::meanStdDev(shot, mean, stddev);
  EXPECT_GT(stddev[0], 10.0);  // not a blank page
  EXPECT_NE(open("broken.html", dir / "broken.png").find("image not found"), std::string::npos);
}
