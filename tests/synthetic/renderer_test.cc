// Renderer geometry: exact depth, texture placement, distortion model.

#include "ddl/synthetic/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "ddl/synthetic/motion.h"
#include "ddl/synthetic/scene.h"
#include "ddl/synthetic/sequence.h"
#include "half_resolution.h"

namespace ddl::synthetic {
namespace {

camera::PinholeCamera small_camera() { return test_support::half_resolution(tum3_camera()); }

/// A 4 m x 3 m wall with a single white square marker of side `marker_m` centred at the wall's
/// centre, on black.
Scene marker_wall(double marker_m) {
  Scene scene;
  const int px = 4000;  // 1 mm texels
  cv::Mat img(3000, px, CV_8UC3, cv::Scalar(0, 0, 0));
  const int half = static_cast<int>(marker_m * 1000 / 2);
  img(cv::Rect(2000 - half, 1500 - half, 2 * half, 2 * half)).setTo(cv::Scalar(255, 255, 255));
  scene.add_texture(make_texture(img, {}, "test:marker"));
  Surface s = make_rect(Vec3d(0, 3, 1.5), Vec3d(0, -1, 0), Vec3d::UnitZ(), 4.0, 3.0, 0);
  s.shade = 1.0f;
  scene.surfaces.push_back(s);
  return scene;
}

TEST(Renderer, PlaneDepthEqualsAnalyticDepth) {
  const camera::PinholeCamera cam = small_camera();
  const Renderer renderer(cam);
  Scene scene;
  scene.add_texture(make_texture(cv::Mat(64, 64, CV_8UC3, cv::Scalar(90, 120, 200)), {}, "flat"));
  // A large tilted plane: normal (0.3, -1, 0.2), through (0, 2.5, 1).
  const Vec3d n = Vec3d(0.3, -1.0, 0.2).normalized();
  scene.surfaces.push_back(make_rect(Vec3d(0, 2.5, 1), n, Vec3d::UnitZ(), 20, 20, 0));
  const SE3 T_w_c(look_at_rotation(Vec3d(0.2, 0, 1.2), Vec3d(0.5, 3, 0.8)), Vec3d(0.2, 0, 1.2));
  const SE3 T_c_w = T_w_c.inverse();
  const PreparedSurfaces prepared(scene.surfaces, scene.textures, T_c_w);
  RenderBuffers buffers = renderer.make_buffers();
  renderer.rasterize(prepared, 0, 1, buffers);
  // Analytic: plane n_c . p = d_c with p = z * ray.
  const Vec3d n_c = T_c_w.rotation() * n;
  const double d_c = n_c.dot(T_c_w * Vec3d(0, 2.5, 1));
  double max_error = 0.0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Vec3d ray = renderer.ray(u, v);
      const double z = d_c / n_c.dot(ray);
      ASSERT_EQ(buffers.id.at<int>(v, u), 0) << u << "," << v;
      max_error = std::max(max_error, std::abs(buffers.depth_m.at<float>(v, u) - z));
    }
  }
  EXPECT_LT(max_error, 1e-4);
}

TEST(Renderer, UnprojectedDepthLiesOnTheVisibleSurface) {
  // The standard room seen along the xyz motion: every pixel's depth, unprojected with the pose,
  // lies on the plane (and inside the rectangle) of the surface the id buffer names, and
  // projects back onto the pixel.
  const camera::PinholeCamera cam = small_camera();
  const Renderer renderer(cam);
  Rng rng(5);
  RoomOptions options;
  options.texel_m = 0.01;
  const Scene scene = build_room(options, RoomLayout{}, rng);
  MotionConfig motion;
  motion.type = MotionType::kXyz;
  for (double t : {0.0, 3.3, 7.1}) {
    const SE3 T_w_c = camera_pose(motion, t);
    const SE3 T_c_w = T_w_c.inverse();
    const PreparedSurfaces prepared(scene.surfaces, scene.textures, T_c_w);
    RenderBuffers buffers = renderer.make_buffers();
    renderer.rasterize(prepared, 0, scene.surfaces.size(), buffers);
    double max_plane = 0.0;
    double max_reprojection = 0.0;
    int checked = 0;
    for (int v = 0; v < cam.height; v += 3) {
      for (int u = 0; u < cam.width; u += 3) {
        const int id = buffers.id.at<int>(v, u);
        ASSERT_GE(id, 0) << "the closed room covers every pixel";
        const double z = buffers.depth_m.at<float>(v, u);
        const Vec3d p_w = T_w_c * cam.unproject(u, v, z);
        const Surface& s = scene.surfaces[static_cast<std::size_t>(id)];
        const Vec3d n = s.u_w.cross(s.v_w).normalized();
        max_plane = std::max(max_plane, std::abs(n.dot(p_w - s.origin_w)));
        const double a = (p_w - s.origin_w).dot(s.u_w) / s.u_w.squaredNorm();
        const double b = (p_w - s.origin_w).dot(s.v_w) / s.v_w.squaredNorm();
        EXPECT_TRUE(a > -1e-4 && a < 1 + 1e-4 && b > -1e-4 && b < 1 + 1e-4);
        const Vec2d uv = cam.project(T_c_w * p_w);
        max_reprojection = std::max(max_reprojection, (uv - Vec2d(u, v)).norm());
        ++checked;
      }
    }
    EXPECT_GT(checked, 8000);
    EXPECT_LT(max_plane, 1e-4) << "t = " << t;
    EXPECT_LT(max_reprojection, 1e-3) << "t = " << t;
  }
}

TEST(Renderer, MarkerIsRenderedWhereItsWorldPositionProjects) {
  // A 6 cm white square on a black wall, seen frontally and obliquely: the intensity centroid of
  // the rendered square is the projection of the square's centre (perspective-correct texture
  // placement; the centroid of a small projected square differs from the projected centre by
  // far less than 0.05 px at these distances).
  const camera::PinholeCamera cam = tum3_camera();
  const Renderer renderer(cam);
  const Scene scene = marker_wall(0.06);
  const Vec3d marker_w(0, 3, 1.5);
  const Vec3d positions[] = {{0.1, 0.8, 1.4}, {-1.2, 1.2, 1.0}, {0.9, 1.6, 2.1}};
  for (const auto& position : positions) {
    for (double roll : {0.0, 0.4}) {
      const Vec3d look = marker_w + Vec3d(0.15, 0, -0.1);
      const SE3 T_w_c(look_at_rotation(position, look) * so3_exp(Vec3d(0, 0, roll)), position);
      const SE3 T_c_w = T_w_c.inverse();
      const PreparedSurfaces prepared(scene.surfaces, scene.textures, T_c_w);
      RenderBuffers buffers = renderer.make_buffers();
      renderer.rasterize(prepared, 0, 1, buffers);
      cv::Mat rgb;
      cv::Mat cos_incidence;
      renderer.shade(prepared, buffers, 0, rgb, cos_incidence);
      cv::Mat gray;
      cv::cvtColor(rgb, gray, cv::COLOR_BGR2GRAY);
      const cv::Moments m = cv::moments(gray, false);
      ASSERT_GT(m.m00, 255.0 * 50) << "marker not visible";
      const Vec2d centroid(m.m10 / m.m00, m.m01 / m.m00);
      const Vec2d expected = cam.project(T_c_w * marker_w);
      EXPECT_LT((centroid - expected).norm(), 0.5)
          << "camera at " << position.transpose() << " roll " << roll << ": centroid "
          << centroid.transpose() << " expected " << expected.transpose();
    }
  }
}

TEST(Renderer, DistortedCameraRaysInvertOpenCvProjection) {
  // Rendering into a distorted image: the ray of pixel (u, v) must project back onto (u, v)
  // through cv::projectPoints with the same coefficients.
  const camera::PinholeCamera cam = tum1_camera();
  const Renderer renderer(cam);
  std::vector<cv::Point3d> points;
  std::vector<cv::Point2d> pixels;
  for (int v = 0; v < cam.height; v += 37) {
    for (int u = 0; u < cam.width; u += 41) {
      const Vec3d r = renderer.ray(u, v);
      points.emplace_back(r.x() * 2.0, r.y() * 2.0, 2.0);
      pixels.emplace_back(u, v);
    }
  }
  std::vector<cv::Point2d> projected;
  const cv::Mat dist(1, 5, CV_64F, const_cast<double*>(cam.distortion.data()));
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(cam.K()), dist,
                    projected);
  double max_error = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    max_error = std::max(max_error, cv::norm(projected[i] - pixels[i]));
  }
  EXPECT_LT(max_error, 1e-3);
}

TEST(Renderer, CutOutTexturesCoverOnlyTheirMask) {
  // A billboard whose texture's coverage is a disc: rendered pixels are exactly those whose
  // texture coordinates fall inside the disc (checked through the s/t buffers).
  const camera::PinholeCamera cam = small_camera();
  const Renderer renderer(cam);
  Scene scene;
  cv::Mat alpha(200, 200, CV_8UC1, cv::Scalar(0));
  cv::circle(alpha, {100, 100}, 80, cv::Scalar(255), cv::FILLED);
  scene.add_texture(make_texture(cv::Mat(200, 200, CV_8UC3, cv::Scalar(0, 200, 0)), alpha, "disc"));
  scene.surfaces.push_back(make_rect(Vec3d(0, 2, 1.2), Vec3d(0, -1, 0), Vec3d::UnitZ(), 1, 1, 0));
  const Vec3d position(0, 0, 1.2);
  const SE3 T_w_c(look_at_rotation(position, Vec3d(0, 2, 1.2)), position);
  const PreparedSurfaces prepared(scene.surfaces, scene.textures, T_w_c.inverse());
  RenderBuffers buffers = renderer.make_buffers();
  renderer.rasterize(prepared, 0, 1, buffers);
  int inside = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (buffers.id.at<int>(v, u) != 0) continue;
      ++inside;
      const double s = buffers.s.at<float>(v, u) * 200 - 100;
      const double t = buffers.t.at<float>(v, u) * 200 - 100;
      EXPECT_LT(std::hypot(s, t), 81.5);
    }
  }
  // Disc of radius 0.4 m at 2 m: about pi * (0.4 * 267.7 / 2)^2 pixels.
  const double expected = M_PI * std::pow(0.4 * cam.fx / 2.0, 2);
  EXPECT_NEAR(inside, expected, 0.03 * expected);
}

}  // namespace
}  // namespace ddl::synthetic
