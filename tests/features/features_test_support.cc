#include "features_test_support.h"

#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "shared_data.h"

namespace ddl::features::test {

std::filesystem::path shared_dir() { return test_support::shared_dir(); }

std::filesystem::path tum_rpy_dir() {
  return shared_dir() / "data" / "tum" / "rgbd_dataset_freiburg1_rpy";
}

cv::Mat load_tum_rpy_gray(int index, std::string* path_out) {
  const std::filesystem::path list = tum_rpy_dir() / "rgb.txt";
  if (path_out != nullptr) *path_out = list.string();
  std::ifstream in(list);
  if (!in) return {};
  std::string line;
  int seen = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (seen++ != index) continue;
    const std::size_t space = line.find(' ');
    if (space == std::string::npos) return {};
    const std::filesystem::path file = tum_rpy_dir() / line.substr(space + 1);
    if (path_out != nullptr) *path_out = file.string();
    return cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  }
  return {};
}

cv::Mat make_textured_image(cv::Size size, std::uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat image(size, CV_8UC1, cv::Scalar(128));
  const int num_shapes = size.area() / 500;
  auto random_size = [&] {
    // Log-uniform sizes give structure at every pyramid level.
    return static_cast<int>(std::exp(rng.uniform(std::log(4.0), std::log(90.0))));
  };
  for (int k = 0; k < num_shapes; ++k) {
    const cv::Point c(rng.uniform(-20, size.width + 20), rng.uniform(-20, size.height + 20));
    const cv::Scalar grey(rng.uniform(0, 256));
    const int s = random_size();
    switch (rng.uniform(0, 4)) {
      case 0:
        cv::rectangle(image, cv::Rect(c.x, c.y, s, random_size()), grey, cv::FILLED);
        break;
      case 1:
        cv::ellipse(image, c, cv::Size(s, random_size() / 2 + 2), rng.uniform(0.0, 180.0), 0, 360,
                    grey, cv::FILLED, cv::LINE_AA);
        break;
      case 2: {
        std::vector<cv::Point> tri;
        for (int i = 0; i < 3; ++i)
          tri.emplace_back(c.x + rng.uniform(-s, s), c.y + rng.uniform(-s, s));
        cv::fillConvexPoly(image, tri, grey, cv::LINE_AA);
        break;
      }
      default:
        cv::line(image, c, c + cv::Point(rng.uniform(-s, s), rng.uniform(-s, s)), grey,
                 rng.uniform(1, 4), cv::LINE_AA);
        break;
    }
  }
  cv::GaussianBlur(image, image, cv::Size(3, 3), 0.7);
  return image;
}

}  // namespace ddl::features::test
