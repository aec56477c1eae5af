// Preview renderer against its closed-form shading: a quad of known colour seen straight down.

#include "scene/preview.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "scene/default_scene.hpp"
#include "scene/scene.hpp"

namespace sc = radar_emu::scene;

namespace {

// sRGB encoding (IEC 61966-2-1) of a linear value, to 8 bits.
int srgb8(double v) {
  const double e = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
  return static_cast<int>(std::lround(255.0 * e));
}

sc::SceneDescription quad_scene(glm::vec3 colour, float half_m) {
  sc::SceneDescription d;
  d.materials = {{"concrete", colour}};
  sc::ObjectDesc o;
  o.name = "quad";
  o.mesh.positions_m = {
      {-half_m, -half_m, 0}, {half_m, -half_m, 0}, {half_m, half_m, 0}, {-half_m, half_m, 0}};
  o.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  o.mesh.triangle_material = {0, 0};
  d.objects.push_back(o);
  return d;
}

int pixel(const sc::PreviewImage& im, int i, int j, int k) {
  return im.rgb[(static_cast<std::size_t>(j) * static_cast<std::size_t>(im.width_px) +
                 static_cast<std::size_t>(i)) *
                    3 +
                static_cast<std::size_t>(k)];
}

}  // namespace

TEST(Preview, QuadSeenStraightDownHasTheShadingFormulasColourAndSkyAroundIt) {
  const glm::vec3 colour(0.8f, 0.4f, 0.1f);
  const sc::Scene scene(quad_scene(colour, 20.0f));
  sc::PreviewCamera cam;
  cam.position_m = {0.0, 0.0, 100.0};
  cam.look_at_m = {0.0, 0.0, 0.0};
  cam.up = {0.0, 1.0, 0.0};
  cam.vertical_fov_rad = 60.0 * std::acos(-1.0) / 180.0;
  cam.width_px = 81;  // odd: the centre pixel's ray is the optical axis
  cam.height_px = 61;
  const sc::PreviewImage im = sc::render_preview(scene, cam);
  ASSERT_EQ(im.width_px, 81);
  ASSERT_EQ(im.height_px, 61);
  ASSERT_EQ(im.rgb.size(), 81u * 61u * 3u);
  // Centre: the quad at t = 100 m, normal +z; c = base (ambient + diffuse sun_z), hazed.
  using Light = sc::PreviewLighting;
  const double sun_z = std::sin(45.0 * std::acos(-1.0) / 180.0);
  EXPECT_NEAR(Light::kSun.z, sun_z, 1e-15);
  const double transmittance = std::exp(-3.912 / Light::kVisibility_m * 100.0);
  for (int k = 0; k < 3; ++k) {
    const double lit = static_cast<double>(colour[k]) * (Light::kAmbient + Light::kDiffuse * sun_z);
    const double expected = lit * transmittance + Light::kSky[k] * (1.0 - transmittance);
    EXPECT_NEAR(pixel(im, 40, 30, k), srgb8(expected), 1) << "channel " << k;
  }
  // Corners: the quad (40 m) is narrower than the view (115 m high, 154 m wide at 100 m): sky.
  for (const auto& [i, j] :
       {std::pair{0, 0}, std::pair{80, 0}, std::pair{0, 60}, std::pair{80, 60}}) {
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(pixel(im, i, j, k), srgb8(Light::kSky[k])) << i << "," << j;
  }
  // The quad's east edge where the pinhole model puts it: x = 20 m at 100 m below is 0.2 off
  // axis; pixel i looks (2 (i + 0.5) / 81 - 1) tan(30 deg) 81/61 off axis: 0.189 for i = 50
  // (quad), 0.208 for i = 51 (sky). Camera right is +x when looking down with +y up.
  EXPECT_NE(pixel(im, 50, 30, 2), srgb8(Light::kSky[2]));
  EXPECT_EQ(pixel(im, 51, 30, 2), srgb8(Light::kSky[2]));
  EXPECT_NE(pixel(im, 30, 30, 2), srgb8(Light::kSky[2]));  // west edge, mirrored
  EXPECT_EQ(pixel(im, 29, 30, 2), srgb8(Light::kSky[2]));
}

TEST(Preview, BadCamerasAreRejectedAndTheDefaultCameraSeesTheScene) {
  const sc::Scene scene(sc::default_scene());
  sc::PreviewCamera cam = sc::default_preview_camera(scene, 64, 48);
  EXPECT_EQ(cam.width_px, 64);
  EXPECT_EQ(cam.height_px, 48);
  // From the south-west and above, looking at the middle of the scene's bounds.
  EXPECT_LT(cam.position_m.x, cam.look_at_m.x);
  EXPECT_LT(cam.position_m.y, cam.look_at_m.y);
  EXPECT_GT(cam.position_m.z, cam.look_at_m.z);
  const sc::PreviewImage im = sc::render_preview(scene, cam);
  // The centre pixel sees the ground, not the sky.
  EXPECT_NE(pixel(im, 32, 24, 2), srgb8(sc::PreviewLighting::kSky[2]));
  sc::PreviewCamera bad = cam;
  bad.width_px = 0;
  EXPECT_THROW((void)sc::render_preview(scene, bad), std::invalid_argument);
  bad = cam;
  bad.look_at_m = bad.position_m;
  EXPECT_THROW((void)sc::render_preview(scene, bad), std::invalid_argument);
  bad = cam;
  bad.up = cam.look_at_m - cam.position_m;
  EXPECT_THROW((void)sc::render_preview(scene, bad), std::invalid_argument);
  bad = cam;
  bad.vertical_fov_rad = std::nan("");
  EXPECT_THROW((void)sc::render_preview(scene, bad), std::invalid_argument);
  EXPECT_THROW((void)sc::default_preview_camera(scene, 20000, 10), std::invalid_argument);
}
