#include <gtest/gtest.h>

#include <fstream>
#include <limits>

#include "core/error.h"
#include "vo/system/odometry_options.h"

namespace dvso::vo {
namespace {

std::string ConfigPath(const std::string& name) {
  return std::string(DVSO_TEST_DATA_DIR) + "/../configs/" + name;
}

TEST(SystemOptions, DefaultsAreDsoAndValid) {
  const OdometryOptions o;
  EXPECT_NO_THROW(o.Check());
  EXPECT_EQ(o.active_points, 2000);
  EXPECT_EQ(o.selector.desired_points, 1500);
  EXPECT_EQ(o.window.max_keyframes, 7);
  EXPECT_DOUBLE_EQ(o.tracker.huber_threshold, 9.0);
  EXPECT_EQ(OdometryOptions::Preset("fast").active_points, 800);
  EXPECT_THROW(OdometryOptions::Preset("turbo"), Error);
}

TEST(SystemOptions, CommittedConfigsEqualPresets) {
  for (const std::string preset : {"default", "fast"}) {
    const OdometryOptions loaded = LoadOdometryOptions(ConfigPath("vo_" + preset + ".yaml"), OdometryOptions{});
    EXPECT_EQ(OdometryOptionsToYaml(loaded), OdometryOptionsToYaml(OdometryOptions::Preset(preset))) << preset;
  }
}

TEST(SystemOptions, YamlRoundTripAndPartialOverride) {
  OdometryOptions o = OdometryOptions::Preset("fast");
  o.tracker.huber_threshold = 7.5;
  o.window.max_keyframes = 5;
  o.selector.seed = 7;
  o.immature.gn_threshold = 0.05;
  o.tracker.max_affine_a = std::numeric_limits<double>::infinity();  // allowed: no bound
  const OdometryOptions back = OdometryOptionsFromYamlString(OdometryOptionsToYaml(o));
  EXPECT_EQ(OdometryOptionsToYaml(back), OdometryOptionsToYaml(o));
  // Field by field too, so that a field the YAML leaves out cannot pass as equal text.
  EXPECT_EQ(back.selector.seed, 7u);
  EXPECT_EQ(back.immature.gn_threshold, 0.05);
  EXPECT_EQ(back.tracker.max_affine_a, std::numeric_limits<double>::infinity());
  EXPECT_EQ(back.tracker.huber_threshold, 7.5);
  const OdometryOptions partial = OdometryOptionsFromYamlString("keyframe:\n  max_frames_between: 9\n");
  EXPECT_EQ(partial.keyframe.max_frames_between, 9);
  EXPECT_EQ(partial.active_points, 2000);  // untouched default
}

TEST(SystemOptions, StrictKeysAndCheckedValues) {
  EXPECT_THROW(OdometryOptionsFromYamlString("active_pionts: 100\n"), Error);
  EXPECT_THROW(OdometryOptionsFromYamlString("tracker:\n  hubr: 3\n"), Error);
  EXPECT_THROW(OdometryOptionsFromYamlString("active_points: -5\n"), Error);
  // The window's b_v always comes from dvso.virtual_baseline: naming it is an error that says so.
  try {
    OdometryOptionsFromYamlString("window:\n  virtual_stereo_baseline: 0.3\n");
    ADD_FAILURE() << "window.virtual_stereo_baseline accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("dvso.virtual_baseline"), std::string::npos) << e.what();
  }
  EXPECT_EQ(OdometryOptionsToYaml(OdometryOptions()).find("virtual_stereo_baseline"), std::string::npos);
  // immature.max_steps (DSO's 100-sample cap of the epipolar search) is gone: an old config is told so.
  try {
    OdometryOptionsFromYamlString("immature:\n  max_steps: 100\n");
    ADD_FAILURE() << "immature.max_steps accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("immature.max_steps is no longer a setting"), std::string::npos) << e.what();
  }
  EXPECT_THROW(OdometryOptionsFromYamlString("window:\n  max_keyframes: 1\n"), Error);
  try {
    OdometryOptionsFromYamlString("selector:\n  desired_pts: 3\n");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("selector.desired_pts"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace dvso::vo
