#pragma once
// The synthetic renderer: exact per-pixel ray/rectangle intersection with a z-buffer (no
// triangles, no rasterisation approximations), then deferred texturing with perspective-correct
// coordinates (they come from the 3-D intersection point) and trilinear mip-mapped sampling.
//
// Camera model: pixel (u, v) looks along the ray (x_n, y_n, 1) in the camera frame, where
// (x_n, y_n) are the undistorted normalised coordinates of the pixel. For a camera without
// distortion x_n = (u - cx) / fx; with distortion they are found by inverting the Brown-Conrady
// model (cv::undistortPoints), so rendering into a distorted image is consistent with
// cv::projectPoints / an undistortion by the same coefficients. Depth is z along the optical axis.
//
// Threads: a Renderer is immutable after construction; its const methods may run concurrently
// with different buffers. Work inside one call is split over rows with cv::parallel_for_; each
// pixel's result depends only on that pixel, so the output is identical for any thread count.

#include <opencv2/core.hpp>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"
#include "ddl/synthetic/scene.h"

namespace ddl::synthetic {

/// Per-pixel results of visibility: what is seen where.
struct RenderBuffers {
  cv::Mat depth_m;  // CV_32FC1, z along the optical axis, 0 where nothing was hit
  cv::Mat id;       // CV_32SC1, index of the visible surface in the surface list, -1 = none
  cv::Mat s;        // CV_32FC1, texture column coordinate in [0, 1] (after tex_rect and sway)
  cv::Mat t;        // CV_32FC1, texture row coordinate in [0, 1]
  /// Deep copy.
  RenderBuffers clone() const;
};

/// A surface list prepared for one camera pose (camera-frame plane and texture equations).
class PreparedSurfaces {
 public:
  PreparedSurfaces(const std::vector<Surface>& surfaces, const std::vector<Texture>& textures,
                   const SE3& T_c_w);
  struct Plane {
    float n[3];   // unit normal in the camera frame
    float d;      // plane: n . p = d
    float ua[3];  // a (0..1 along u) = t * (ua . ray) - ua0
    float ua0;
    float vb[3];  // b (0..1 along v) = t * (vb . ray) - vb0
    float vb0;
    float texel_m;  // metric size of a level-0 texel
    bool alpha;     // the texture has a coverage mask (cut-out)
  };
  const std::vector<Surface>& surfaces() const { return *surfaces_; }
  const std::vector<Texture>& textures() const { return *textures_; }
  const Plane& plane(std::size_t i) const { return planes_[i]; }
  std::size_t size() const { return planes_.size(); }
  const SE3& T_c_w() const { return T_c_w_; }

 private:
  const std::vector<Surface>* surfaces_;
  const std::vector<Texture>* textures_;
  std::vector<Plane> planes_;
  SE3 T_c_w_;
};

class Renderer {
 public:
  /// Throws ddl::ConfigError (via camera.validate()) for an invalid camera.
  explicit Renderer(const camera::PinholeCamera& camera, double near_m = 0.05);

  const camera::PinholeCamera& camera() const { return camera_; }

  /// Empty buffers of the camera's size.
  RenderBuffers make_buffers() const;

  /// Z-buffered visibility of surfaces [begin, end) of `prepared` into `buffers`: a pixel takes a
  /// surface when the ray hits it nearer than what the pixel holds (cut-out textures: only where
  /// coverage >= 50%). Ties keep the earlier surface.
  void rasterize(const PreparedSurfaces& prepared, std::size_t begin, std::size_t end,
                 RenderBuffers& buffers) const;

  /// Texture colour times surface shade for every pixel with id >= min_id (others untouched in
  /// `rgb`, which must be CV_8UC3 of the camera's size or empty: then it is allocated black).
  /// `cos_incidence` (CV_32FC1, same rule) receives |cos| of the angle between ray and normal.
  void shade(const PreparedSurfaces& prepared, const RenderBuffers& buffers, int min_id,
             cv::Mat& rgb, cv::Mat& cos_incidence) const;

  /// The ray of pixel (u, v): (x_n, y_n, 1) in the camera frame.
  Vec3d ray(int u, int v) const;

 private:
  camera::PinholeCamera camera_;
  double near_m_;
  bool distorted_;
  cv::Mat ray_x_;  // CV_32FC1 x_n per pixel
  cv::Mat ray_y_;  // CV_32FC1 y_n per pixel
};

}  // namespace ddl::synthetic
