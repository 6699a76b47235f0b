// Unit tests of the data layer: cameras, trajectories, maps, sequence readers, strict YAML.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <limits>
#include <tuple>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/camera.h"
#include "core/config_yaml.h"
#include "core/disparity_io.h"
#include "core/disparity_source.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "core/lie.h"
#include "core/sequence.h"
#include "core/sequence_common.h"
#include "core/trajectory.h"
#include "tests/temp_dir.h"

namespace fs = std::filesystem;
using namespace dvso;

namespace {

std::string TempDir(const std::string& name) {
  return dvso::testing::ScratchDir(name);
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

cv::Mat RandomImage(int w, int h, int seed) {
  cv::Mat img(h, w, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, 0, 255);
  return img;
}

// A tiny KITTI-layout sequence of `n` frames, w x h.
std::string MakeKittiSequence(const std::string& name, int n, int w, int h) {
  const std::string root = TempDir(name);
  fs::create_directories(root + "/image_0");
  fs::create_directories(root + "/image_1");
  StereoCamera cam;
  cam.left = PinholeCamera{100.0, 101.0, w / 2.0, h / 2.0, w, h};
  cam.baseline = 0.5;
  WriteKittiCalibration(root + "/calib.txt", cam);
  std::string times;
  for (int i = 0; i < n; ++i) {
    cv::imwrite(root + "/image_0/" + FrameFileName(i, ".png"), RandomImage(w, h, i));
    cv::imwrite(root + "/image_1/" + FrameFileName(i, ".png"), RandomImage(w, h, 100 + i));
    times += std::to_string(0.25 * i) + "\n";
  }
  WriteText(root + "/times.txt", times);
  return root;
}

}  // namespace

// `dvso simulate` checks a raw drive's calibration before it writes calib.txt: the camera it checks with
// must be, to the last bit, the one a reader gets back from that file (12 significant digits).
TEST(KittiCalibration, AsReadBackIsWhatTheReaderReadsFromTheWrittenFile) {
  const std::string root = TempDir("kitti_calib_read_back");
  StereoCamera cam;
  cam.left = PinholeCamera{718.856 * 160.0 / 1241.0, 718.856 / 3.0, 607.1928 / 7.0, 185.2157 / 3.0, 160, 64};
  cam.baseline = 0.54 / 3.0;
  WriteKittiCalibration(root + "/calib.txt", cam);
  const StereoCamera read = ReadKittiCalibration(root + "/calib.txt", 160, 64);
  const StereoCamera predicted = KittiCalibrationAsReadBack(cam);
  EXPECT_EQ(predicted.left.fx, read.left.fx);
  EXPECT_EQ(predicted.left.fy, read.left.fy);
  EXPECT_EQ(predicted.left.cx, read.left.cx);
  EXPECT_EQ(predicted.left.cy, read.left.cy);
  EXPECT_EQ(predicted.baseline, read.baseline);
  EXPECT_EQ(predicted.left.width, 160);
  EXPECT_EQ(predicted.left.height, 64);
  EXPECT_NE(read.baseline, cam.baseline) << "the file rounds: the test must not pass with the camera itself";
}

TEST(Camera, ResizeKeepsPixelCentres) {
  PinholeCamera cam{500, 400, 319.5, 239.5, 640, 480};
  const PinholeCamera half = cam.Resized(320, 240);
  EXPECT_DOUBLE_EQ(half.fx, 250);
  EXPECT_DOUBLE_EQ(half.fy, 200);
  // The image centre stays the image centre.
  EXPECT_DOUBLE_EQ(half.cx, 159.5);
  EXPECT_DOUBLE_EQ(half.cy, 119.5);
  // A 3D point projects to corresponding positions: u' = (u + 0.5) * s - 0.5.
  const Eigen::Vector3d p(0.3, -0.2, 2.0);
  const Eigen::Vector2d a = cam.Project(p), b = half.Project(p);
  EXPECT_NEAR(b.x(), (a.x() + 0.5) * 0.5 - 0.5, 1e-12);
  EXPECT_NEAR(b.y(), (a.y() + 0.5) * 0.5 - 0.5, 1e-12);
}

TEST(Camera, CropShiftsPrincipalPointAndRejectsOutside) {
  PinholeCamera cam{500, 500, 300, 200, 640, 480};
  const PinholeCamera c = cam.Cropped(10, 20, 600, 400);
  EXPECT_DOUBLE_EQ(c.cx, 290);
  EXPECT_DOUBLE_EQ(c.cy, 180);
  EXPECT_EQ(c.width, 600);
  EXPECT_THROW(cam.Cropped(100, 0, 600, 480), Error);
  PinholeCamera bad = cam;
  bad.fx = -1;
  EXPECT_THROW(bad.Check(), Error);
}

TEST(Camera, DsoCameraFileRoundTripAndRelativeIntrinsics) {
  const std::string dir = TempDir("camfile");
  PinholeCamera cam{718.856, 718.856, 607.1928, 185.2157, 1241, 376};
  WriteDsoCameraFile(dir + "/camera.txt", cam);
  const PinholeCamera back = ReadDsoCameraFile(dir + "/camera.txt");
  EXPECT_NEAR(back.fx, cam.fx, 1e-6);
  EXPECT_NEAR(back.cy, cam.cy, 1e-6);
  EXPECT_EQ(back.width, 1241);
  WriteText(dir + "/rel.txt", "0.5 0.5 0.5 0.5 0\n640 480\nnone\n640 480\n");
  const PinholeCamera rel = ReadDsoCameraFile(dir + "/rel.txt");
  EXPECT_DOUBLE_EQ(rel.fx, 320);
  EXPECT_DOUBLE_EQ(rel.cx, 319.5);
  WriteText(dir + "/fov.txt", "FOV 0.5 0.5 0.5 0.5 0.9\n640 480\n");
  EXPECT_THROW(ReadDsoCameraFile(dir + "/fov.txt"), Error);
}

TEST(Camera, DsoCameraFileOutputLinesAreReadAndAResampledOutputIsSaid) {
  const std::string dir = TempDir("camfile_out");
  const std::string k = "Pinhole 718.856 718.856 607.1928 185.2157 0\n1241 376\n";
  // Without distortion crop / full / none at the same size, or the input's own intrinsics, change nothing.
  for (const std::string out : {"crop\n1241 376\n", "full\n1241 376\n", "none\n1241 376\n",
                                "718.856 718.856 607.1928 185.2157 0\n1241 376\n", ""}) {
    WriteText(dir + "/same.txt", k + out);
    ::testing::internal::CaptureStderr();
    const PinholeCamera cam = ReadDsoCameraFile(dir + "/same.txt");
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "") << out;
    EXPECT_DOUBLE_EQ(cam.fx, 718.856) << out;
    EXPECT_EQ(cam.width, 1241) << out;
  }
  // An output DSO would resample to: the input is tracked as it is (same poses), and the run says so.
  for (const std::string out : {"crop\n640 192\n", "none\n620 188\n", "500 500 320 96 0\n1241 376\n"}) {
    WriteText(dir + "/other.txt", k + out);
    ::testing::internal::CaptureStderr();
    const PinholeCamera cam = ReadDsoCameraFile(dir + "/other.txt");
    const std::string warning = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(warning.find("other.txt"), std::string::npos) << out;
    EXPECT_NE(warning.find("not resampled"), std::string::npos) << warning;
    EXPECT_DOUBLE_EQ(cam.fx, 718.856) << out;
    EXPECT_EQ(cam.width, 1241) << out;
  }
  // Lines that are not DSO's format are errors naming the file.
  for (const std::string out : {"crop\n", "stretch\n1241 376\n", "crop\n1241\n"}) {
    WriteText(dir + "/bad.txt", k + out);
    try {
      ReadDsoCameraFile(dir + "/bad.txt");
      ADD_FAILURE() << "accepted: " << out;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("bad.txt"), std::string::npos) << e.what();
    }
  }
}

TEST(Lie, ExpLogRoundTrip) {
  Vector6d xi;
  xi << 0.3, -0.2, 1.5, 0.1, -0.4, 0.25;
  const Eigen::Isometry3d T = ExpSE3(xi);
  EXPECT_TRUE(LogSE3(T).isApprox(xi, 1e-10));
  EXPECT_NEAR(RotationAngle(T.linear()), xi.tail<3>().norm(), 1e-12);
}

TEST(Trajectory, KittiAndTumRoundTrip) {
  const std::string dir = TempDir("traj");
  Trajectory t;
  for (int i = 0; i < 5; ++i) {
    Vector6d xi;
    xi << i * 1.0, 0.1 * i, -0.5 * i, 0.01 * i, 0.2 * i, -0.03 * i;
    t.poses.push_back({0.1 * i, ExpSE3(xi)});
  }
  WriteKittiTrajectory(dir + "/k.txt", t);
  WriteTumTrajectory(dir + "/t.txt", t);
  const Trajectory k = ReadTrajectory(dir + "/k.txt");
  const Trajectory u = ReadTrajectory(dir + "/t.txt");
  ASSERT_EQ(k.size(), 5u);
  ASSERT_EQ(u.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_TRUE(k.poses[i].T_world_camera.isApprox(t.poses[i].T_world_camera, 1e-9));
    EXPECT_TRUE(u.poses[i].T_world_camera.isApprox(t.poses[i].T_world_camera, 1e-9));
    EXPECT_DOUBLE_EQ(k.poses[i].timestamp, i);  // KITTI: line index
    EXPECT_NEAR(u.poses[i].timestamp, 0.1 * i, 1e-12);
  }
  EXPECT_NEAR(t.PathLength(), k.PathLength(), 1e-9);
  // A times file gives KITTI poses their timestamps; beside a TUM file (own timestamps) it is an error.
  const std::vector<double> times = {10.0, 10.1, 10.2, 10.3, 10.4};
  EXPECT_DOUBLE_EQ(ReadTrajectory(dir + "/k.txt", TrajectoryFormat::kAuto, &times).poses[3].timestamp, 10.3);
  EXPECT_THROW(ReadTrajectory(dir + "/t.txt", TrajectoryFormat::kAuto, &times), Error);
  const std::vector<double> short_times = {10.0};
  EXPECT_THROW(ReadTrajectory(dir + "/k.txt", TrajectoryFormat::kAuto, &short_times), Error);
}

TEST(Trajectory, RealKittiPosesLoad) {
  const Trajectory t = ReadTrajectory(std::string(DVSO_TEST_DATA_DIR) + "/kitti_poses/04.txt");
  EXPECT_EQ(t.size(), 271u);
  EXPECT_TRUE(t.poses[0].T_world_camera.isApprox(Eigen::Isometry3d::Identity(), 1e-6));
  EXPECT_GT(t.PathLength(), 300.0);  // sequence 04 is a ~394 m straight drive
}

TEST(Trajectory, MalformedInputNamesFileAndLine) {
  const std::string dir = TempDir("trajbad");
  WriteText(dir + "/bad.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 nan 0 0 1 0\n");
  try {
    ReadTrajectory(dir + "/bad.txt");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.txt"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos);
  }
  WriteText(dir + "/empty.txt", "# nothing\n");
  EXPECT_THROW(ReadTrajectory(dir + "/empty.txt"), Error);
  EXPECT_THROW(ReadTrajectory(dir + "/missing.txt"), Error);
}

TEST(DisparityIo, KittiPngRoundTripQuantisesTo1Over256) {
  const std::string dir = TempDir("disp");
  cv::Mat map(4, 5, CV_32F, cv::Scalar(0));
  map.at<float>(0, 0) = 12.345f;
  map.at<float>(1, 2) = 0.001f;  // positive but tiny: must stay valid
  map.at<float>(3, 4) = -3.f;    // invalid
  map.at<float>(2, 1) = std::numeric_limits<float>::quiet_NaN();
  WriteKittiMapPng(dir + "/d.png", map);
  const cv::Mat back = ReadKittiMapPng(dir + "/d.png");
  EXPECT_NEAR(back.at<float>(0, 0), 12.345f, 0.5f / 256);
  EXPECT_FLOAT_EQ(back.at<float>(1, 2), 1.f / 256);
  EXPECT_FLOAT_EQ(back.at<float>(3, 4), 0.f);
  EXPECT_FLOAT_EQ(back.at<float>(2, 1), 0.f);
  EXPECT_FALSE(fs::exists(dir + "/d.tmp-writing.png"));
  // The temporary-file names WriteAtomically uses, with and without an extension, and nothing else.
  EXPECT_TRUE(IsUnfinishedAtomicWrite("out/000001.tmp-writing.png"));
  EXPECT_TRUE(IsUnfinishedAtomicWrite("out/INTERRUPTED.tmp-writing"));
  EXPECT_FALSE(IsUnfinishedAtomicWrite("out/000001.png"));
  EXPECT_FALSE(IsUnfinishedAtomicWrite("out/tmp-writing.png"));
  EXPECT_FALSE(IsUnfinishedAtomicWrite("out/INTERRUPTED"));
  // NormalizedFolderPath: the folder's own name whatever the spelling.
  for (const std::string& spelling : {dir, dir + "/", dir + "/.", dir + "/../" + fs::path(dir).filename().string()}) {
    EXPECT_EQ(NormalizedFolderPath(spelling).filename(), fs::path(dir).filename()) << spelling;
  }
  EXPECT_EQ(NormalizedFolderPath(".").filename(), fs::current_path().filename());
  // An 8-bit PNG is not a KITTI map.
  cv::imwrite(dir + "/eight.png", cv::Mat(3, 3, CV_8U, cv::Scalar(7)));
  EXPECT_THROW(ReadKittiMapPng(dir + "/eight.png"), Error);
}

// An ofstream holds the last few KB until close(): a full disk (here a file-size limit) shows only
// there. A writer that checked the stream before closing renamed a truncated trajectory into place.
TEST(FsUtil, WriteThatFailsAtCloseLeavesNoFile) {
  const std::string dir = TempDir("atomic_close_failure");
  Trajectory trajectory;
  for (int i = 0; i < 20; ++i) {
    StampedPose pose;
    pose.timestamp = 0.1 * i;
    pose.T_world_camera.translation() = Eigen::Vector3d(0.1 * i, 0.0, 1.0 * i);
    trajectory.poses.push_back(pose);
  }
  struct rlimit saved;
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &saved), 0);
  void (*previous)(int) = std::signal(SIGXFSZ, SIG_IGN);  // EFBIG instead of the signal
  struct rlimit limited = saved;
  limited.rlim_cur = 512;  // bytes: 20 poses need ~2 KB, all of it still in the stream's buffer
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limited), 0);
  bool threw = false;
  try {
    WriteKittiTrajectory(dir + "/trajectory.txt", trajectory);
  } catch (const Error& e) {
    threw = true;
    EXPECT_NE(std::string(e.what()).find(dir + "/trajectory.txt"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find(kAtomicWriteTag), std::string::npos) << "names the temporary file";
  }
  // cv::imwrite ignores its close too: a 16-bit map of noise (~20 KB) reported success cut at 512 bytes.
  cv::Mat map(100, 100, CV_32F);
  cv::randu(map, 1.0f, 200.0f);
  bool map_threw = false;
  try {
    WriteKittiMapPng(dir + "/map.png", map);
  } catch (const Error&) {
    map_threw = true;
  }
  setrlimit(RLIMIT_FSIZE, &saved);
  std::signal(SIGXFSZ, previous);
  EXPECT_TRUE(threw);
  EXPECT_TRUE(map_threw);
  EXPECT_FALSE(fs::exists(dir + "/trajectory.txt"));
  EXPECT_FALSE(fs::exists(dir + "/trajectory.tmp-writing.txt"));
  EXPECT_FALSE(fs::exists(dir + "/map.png"));
  EXPECT_FALSE(fs::exists(dir + "/map.tmp-writing.png"));
  // Without the limit the same call writes every pose.
  WriteKittiTrajectory(dir + "/trajectory.txt", trajectory);
  EXPECT_EQ(ReadTrajectory(dir + "/trajectory.txt", TrajectoryFormat::kKitti).size(), 20u);
}

TEST(DisparityIo, RealKitti2015GroundTruthReads) {
  const cv::Mat gt = ReadKittiMapPng(std::string(DVSO_TEST_DATA_DIR) + "/kitti_stereo_2015_sample/disp_occ_0/000046_10.png");
  EXPECT_EQ(gt.cols, 1242);
  EXPECT_EQ(gt.rows, 375);
  double max_value = 0;
  cv::minMaxLoc(gt, nullptr, &max_value);
  EXPECT_GT(max_value, 10.0);
  EXPECT_LT(max_value, 256.0);
  EXPECT_GT(cv::countNonZero(gt), 10000);
}

TEST(DisparityIo, NpyStackIsScaledByWidthAndResized) {
  const std::string dir = TempDir("npy");
  std::vector<cv::Mat> maps;
  for (int i = 0; i < 3; ++i) maps.push_back(cv::Mat(4, 8, CV_32F, cv::Scalar(0.01 * (i + 1))));
  WriteNpyStack(dir + "/d.npy", maps);
  NpyDisparityStack stack(dir + "/d.npy");
  EXPECT_EQ(stack.size(), 3);
  EXPECT_EQ(stack.height(), 4);
  EXPECT_EQ(stack.width(), 8);
  const cv::Mat f = stack.Frame(2, 16, 8);
  EXPECT_EQ(f.cols, 16);
  EXPECT_NEAR(f.at<float>(3, 5), 0.03 * 16, 1e-5);
  EXPECT_THROW(stack.Frame(3, 8, 4), Error);
  maps[1].at<float>(2, 2) = std::numeric_limits<float>::quiet_NaN();
  WriteNpyStack(dir + "/nan.npy", maps);
  NpyDisparityStack with_nan(dir + "/nan.npy");
  EXPECT_NO_THROW(with_nan.Frame(0, 8, 4));
  EXPECT_EQ(with_nan.Frame(1, 8, 4).at<float>(2, 2), 0.0f);  // a NaN prediction is "no depth", not an error
  WriteText(dir + "/not.npy", "hello");
  EXPECT_THROW(NpyDisparityStack(dir + "/not.npy"), Error);
}

// A version-1 .npy file with the given header dict and `floats` zero values.
void WriteRawNpy(const std::string& path, const std::string& dict, size_t floats, int major = 1) {
  std::string header = dict;
  while ((10 + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::ofstream out(path, std::ios::binary);
  out.write("\x93NUMPY", 6);
  out.put(static_cast<char>(major));
  out.put(0);
  out.put(static_cast<char>(header.size() & 0xff));
  out.put(static_cast<char>(header.size() >> 8));
  out << header;
  const std::vector<float> zeros(floats, 0.f);
  out.write(reinterpret_cast<const char*>(zeros.data()), static_cast<std::streamsize>(zeros.size() * sizeof(float)));
}

TEST(DisparityIo, NpyHeadersFromOtherWritersReadOrFailInOneLine) {
  const std::string dir = TempDir("npy_headers");
  // Python 2 wrote long dimensions with an L.
  WriteRawNpy(dir + "/py2.npy", "{'descr': '<f4', 'fortran_order': False, 'shape': (3L, 4L, 8L), }", 3 * 4 * 8);
  const NpyDisparityStack py2(dir + "/py2.npy");
  EXPECT_EQ(py2.size(), 3);
  EXPECT_EQ(py2.width(), 8);
  for (const auto& [name, dict, major] :
       {std::tuple{"empty", "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 0, 8), }", 1},
        std::tuple{"words", "{'descr': '<f4', 'fortran_order': False, 'shape': (3, four, 8), }", 1},
        std::tuple{"version", "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4, 8), }", 4},
        std::tuple{"float64", "{'descr': '<f8', 'fortran_order': False, 'shape': (3, 4, 8), }", 1}}) {
    const std::string path = dir + "/" + name + ".npy";
    WriteRawNpy(path, dict, 3 * 4 * 8 * 2, major);
    try {
      NpyDisparityStack stack(path);
      ADD_FAILURE() << name << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
}

TEST(DisparitySource, FolderSourceResizesAndScales) {
  const std::string dir = TempDir("dsrc");
  fs::create_directories(dir + "/l");
  fs::create_directories(dir + "/r");
  WriteKittiMapPng(dir + "/l/000003.png", cv::Mat(10, 20, CV_32F, cv::Scalar(4.0)));
  WriteKittiMapPng(dir + "/r/000003.png", cv::Mat(10, 20, CV_32F, cv::Scalar(2.0)));
  FileDisparitySource source(dir + "/l", dir + "/r", {"000003"});
  const DisparityPair p = source.Predict(0, cv::Mat(20, 40, CV_8U));
  EXPECT_EQ(p.left.cols, 40);
  EXPECT_FLOAT_EQ(p.left.at<float>(5, 5), 8.0f);
  EXPECT_FLOAT_EQ(p.right.at<float>(5, 5), 4.0f);
  EXPECT_THROW(source.Predict(4, cv::Mat(20, 40, CV_8U)), Error);
}

TEST(SequenceRange, CountPastTheEndIsClampedAndSaidSo) {
  EXPECT_EQ(RunEndFrame(100, 10, 50), 60);
  EXPECT_EQ(CountPastEndWarning(100, 10, 50), "");
  EXPECT_EQ(CountPastEndWarning(100, 10, 90), "");  // exactly to the end
  EXPECT_EQ(CountPastEndWarning(100, 10, -1), "");  // -1 = to the end
  EXPECT_EQ(RunEndFrame(100, 10, 91), 100);
  const std::string w = CountPastEndWarning(100, 10, 91);
  EXPECT_NE(w.find("--count 91 from frame 10"), std::string::npos) << w;
  EXPECT_NE(w.find("running 90 frames"), std::string::npos) << w;
  EXPECT_EQ(RunEndFrame(100, 0, std::numeric_limits<int>::max()), 100);  // no overflow
  EXPECT_NE(CountPastEndWarning(100, 0, std::numeric_limits<int>::max()), "");
}

TEST(SequenceReader, KittiLayoutStreamsFrames) {
  const std::string root = MakeKittiSequence("kitti", 3, 37, 21);  // odd sizes on purpose
  WriteText(root + "/image_0/._000001.png", "macOS metadata beside the frame on a foreign disk");
  auto seq = OpenSequence(root);
  ASSERT_EQ(seq->size(), 3);
  EXPECT_TRUE(seq->is_stereo());
  EXPECT_NEAR(seq->camera().baseline, 0.5, 1e-9);
  EXPECT_NEAR(seq->camera().left.fy, 101.0, 1e-9);
  EXPECT_EQ(seq->camera().left.width, 37);
  EXPECT_NEAR(seq->timestamps()[2], 0.5, 1e-9);
  const StereoFrame f = seq->Read(1);
  EXPECT_EQ(f.left.type(), CV_8UC1);
  EXPECT_EQ(cv::norm(f.left, RandomImage(37, 21, 1), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(f.right, RandomImage(37, 21, 101), cv::NORM_INF), 0.0);
  SequenceReadOptions mono;
  mono.load_right = false;
  EXPECT_TRUE(seq->Read(2, mono).right.empty());
}

TEST(SequenceReader, KittiErrorsNameTheFile) {
  const std::string root = MakeKittiSequence("kittibad", 3, 16, 8);
  cv::imwrite(root + "/image_0/000002.png", RandomImage(17, 8, 0));  // size mismatch
  auto seq = OpenSequence(root);
  try {
    seq->Read(2);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("000002.png"), std::string::npos);
  }
  WriteText(root + "/image_1/000001.png", "not a png");
  EXPECT_THROW(seq->Read(1), Error);
  WriteText(root + "/calib.txt", "P0: 1 2 3\n");
  EXPECT_THROW(OpenSequence(root), Error);
  const std::string empty = TempDir("emptyseq");
  fs::create_directories(empty + "/image_0");
  WriteText(empty + "/calib.txt", "P0: 1 0 1 0 0 1 1 0 0 0 1 0\n");
  EXPECT_THROW(OpenSequence(empty), Error);
  EXPECT_THROW(OpenSequence(TempDir("nolayout")), Error);
}

// KITTI's calib.txt: every P = K [I | t] in rectified camera 0. Made-up numbers with the real layout: the
// grey pair 0.54 m apart, the colour cameras 6 cm beside them and 0.53 m apart.
constexpr const char* kCalibColourBeside =
    "P0: 700 0 30 0 0 700 20 0 0 0 1 0\n"
    "P1: 700 0 30 -378 0 700 20 0 0 0 1 0\n"
    "P2: 700 0 30 42 0 700 20 0 0 0 1 0\n"
    "P3: 700 0 30 -329 0 700 20 0 0 0 1 0\n";

TEST(SequenceReader, KittiCalibrationGivesEachPairItsOwnBaseline) {
  const std::string root = TempDir("calib_pairs");
  WriteText(root + "/calib.txt", kCalibColourBeside);
  EXPECT_NEAR(ReadKittiCalibration(root + "/calib.txt", 60, 40).baseline, 378.0 / 700, 1e-12);
  EXPECT_NEAR(ReadKittiCalibration(root + "/calib.txt", 60, 40, CameraPair::kColour).baseline, (42.0 + 329) / 700,
              1e-12);
  EXPECT_FALSE(KittiColourMatchesGrey(root + "/calib.txt"));
  // The simulator's calib.txt: the colour cameras are the grey ones.
  StereoCamera cam;
  cam.left = PinholeCamera{700.0, 700.0, 30.0, 20.0, 60, 40};
  cam.baseline = 0.54;
  WriteKittiCalibration(root + "/calib.txt", cam);
  EXPECT_TRUE(KittiColourMatchesGrey(root + "/calib.txt"));
  WriteText(root + "/calib.txt", "P0: 700 0 30 0 0 700 20 0 0 0 1 0\nP1: 700 0 30 -378 0 700 20 0 0 0 1 0\n");
  EXPECT_THROW(ReadKittiCalibration(root + "/calib.txt", 60, 40, CameraPair::kColour), Error);
}

// KITTI odometry 00's colour cameras (calib.txt of 2011_10_03) sit a few mm apart along the optical axis:
// P[2][3] = t.z != 0, so P[0][3] = fx t.x + cx t.z. By hand: t.x = (45.38225 - 607.1928 * 3.779761e-3) /
// 718.856 = 0.0599386 and (-337.2877 - 607.1928 * 4.915215e-3) / 718.856 = -0.4733524, b = 0.5332909 m;
// P[0][3] / fx alone gives 0.5323319 m, 0.18 % short (every metric scale from the colour pair with it).
TEST(SequenceReader, ColourBaselineCountsTheCamerasDepthOffset) {
  const std::string root = TempDir("calib_kitti00");
  WriteText(root + "/calib.txt",
            "P0: 7.188560000000e+02 0 6.071928000000e+02 0 0 7.188560000000e+02 1.852157000000e+02 0 0 0 1 0\n"
            "P1: 7.188560000000e+02 0 6.071928000000e+02 -3.861448000000e+02 0 7.188560000000e+02 "
            "1.852157000000e+02 0 0 0 1 0\n"
            "P2: 7.188560000000e+02 0 6.071928000000e+02 4.538225000000e+01 0 7.188560000000e+02 "
            "1.852157000000e+02 -1.130887000000e-01 0 0 1 3.779761000000e-03\n"
            "P3: 7.188560000000e+02 0 6.071928000000e+02 -3.372877000000e+02 0 7.188560000000e+02 "
            "1.852157000000e+02 2.369057000000e+00 0 0 1 4.915215000000e-03\n");
  EXPECT_NEAR(ReadKittiCalibration(root + "/calib.txt", 1241, 376, CameraPair::kColour).baseline, 0.5332909, 1e-7);
  EXPECT_NEAR(ReadKittiCalibration(root + "/calib.txt", 1241, 376).baseline, 386.1448 / 718.856, 1e-12);
  // t.x of the left camera 0, of the right one (-3 - 10 * 0.5) / 2 = -4.
  EXPECT_NEAR(internal::RectifiedBaseline({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}, {2, 0, 10, -3, 0, 2, 0, 0, 0, 0, 1, 0.5}, "calib.txt"),
              4.0, 1e-12);
  // t = K^-1 P[:, 3] with every component: t.z = 0.5, t.y = (1 - 6 * 0.5) / 4 = -0.5, t.x = (-3 - 10 * 0.5) / 2 = -4.
  const cv::Vec3d offset = internal::RectifiedCameraOffset({2, 0, 10, -3, 0, 4, 6, 1, 0, 0, 1, 0.5}, "calib.txt");
  EXPECT_NEAR(offset[0], -4.0, 1e-12);
  EXPECT_NEAR(offset[1], -0.5, 1e-12);
  EXPECT_NEAR(offset[2], 0.5, 1e-12);
  try {
    internal::RectifiedCameraOffset({0, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0}, "calib.txt");
    ADD_FAILURE() << "a singular K was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("calib.txt"), std::string::npos) << e.what();  // names the file
  }
}

// Calibration files from other tools: a byte order mark, blanks around a name, '#' comments.
TEST(SequenceReader, KittiCalibrationOfOtherWritersReads) {
  const std::string root = TempDir("calib_other_writers");
  WriteText(root + "/calib.txt",
            "\xEF\xBB\xBF# written by another renderer\n"
            "P0 : 700 0 30 0 0 700 20 0 0 0 1 0\r\n"
            "  # the right camera\n"
            "\tP1:\t700 0 30 -378 0 700 20 0 0 0 1 0\n");
  const StereoCamera camera = ReadKittiCalibration(root + "/calib.txt", 60, 40);
  EXPECT_NEAR(camera.left.fx, 700, 1e-12);
  EXPECT_NEAR(camera.baseline, 0.54, 1e-12);
}

// A calibration written for other images than the ones beside it (a full-size KITTI calib.txt beside
// downscaled images) runs to a garbage trajectory without any error unless the reader says so: a principal
// point outside the images is an error, one far off their centre (calibration for twice the size) a warning.
TEST(SequenceReader, CalibrationOfAnotherImageSizeIsAnErrorOrAWarning) {
  const std::string root = MakeKittiSequence("calib_other_size", 2, 60, 40);
  WriteText(root + "/calib.txt", kCalibColourBeside);  // centred: cx 30 of 60, cy 20 of 40
  ::testing::internal::CaptureStderr();
  EXPECT_NO_THROW(OpenSequence(root));
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  WriteText(root + "/calib.txt", "P0: 700 0 58 0 0 700 38 0 0 0 1 0\nP1: 700 0 58 -378 0 700 38 0 0 0 1 0\n");
  ::testing::internal::CaptureStderr();
  EXPECT_NO_THROW(OpenSequence(root));
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("far from the centre of the 60x40 images"), std::string::npos);
  WriteText(root + "/calib.txt", "P0: 700 0 120 0 0 700 20 0 0 0 1 0\nP1: 700 0 120 -378 0 700 20 0 0 0 1 0\n");
  try {
    OpenSequence(root);
    FAIL() << "a principal point outside the images must be an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("calib.txt: principal point (120, 20) lies outside the 60x40 images"),
              std::string::npos)
        << e.what();
  }
}

// 16-bit images are read as the full 16-bit range; a 12-bit sensor's values (or 8-bit ones) in a 16-bit PNG
// would read nearly black and lose every frame without a word, so the sequence refuses them when it opens.
TEST(SequenceReader, SixteenBitImagesMustUseTheirRange) {
  const std::string root = MakeKittiSequence("sixteen_bit", 2, 60, 40);
  cv::Mat full;
  RandomImage(60, 40, 0).convertTo(full, CV_16U, 256.0);
  cv::imwrite(root + "/image_0/000000.png", full);
  EXPECT_EQ(cv::norm(OpenSequence(root)->Read(0).left, RandomImage(60, 40, 0), cv::NORM_INF), 0.0);
  cv::Mat twelve_bit(40, 60, CV_16U, cv::Scalar(1000));
  twelve_bit.at<uint16_t>(3, 3) = 4095;
  cv::imwrite(root + "/image_0/000000.png", twelve_bit);
  // A dark first frame among full-range ones (a lens cap, a tunnel) is no 12-bit sequence.
  cv::imwrite(root + "/image_0/000001.png", full);
  EXPECT_NO_THROW(OpenSequence(root));
  cv::imwrite(root + "/image_0/000001.png", twelve_bit);
  try {
    OpenSequence(root);
    FAIL() << "16-bit images of 12-bit values must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("000000.png: 16-bit image whose values stop at 4095"), std::string::npos)
        << e.what();
  }
  // An opaque alpha channel (65535) says nothing about the colours' range.
  cv::Mat rgba;
  cv::cvtColor(twelve_bit, rgba, cv::COLOR_GRAY2BGRA);
  rgba.forEach<cv::Vec4w>([](cv::Vec4w& pixel, const int*) { pixel[3] = 65535; });
  cv::imwrite(root + "/image_0/000000.png", rgba);
  cv::imwrite(root + "/image_0/000001.png", rgba);
  EXPECT_THROW(OpenSequence(root), Error);
}

// A right folder that holds none of the left names (other names, another format, emptied) is no right
// camera: said when the sequence opens, by the commands that need a pair, not once per frame of the run.
TEST(SequenceReader, RightFolderWithoutTheLeftNamesIsNoPair) {
  const std::string root = MakeKittiSequence("right_other_names", 2, 16, 8);
  ASSERT_TRUE(OpenSequence(root)->is_stereo());
  EXPECT_EQ(OpenSequence(root)->NotStereoReason(), "");
  // One missing right image is a lost frame of the run, not a sequence without a pair.
  fs::rename(root + "/image_1/000000.png", root + "/000000_right.png");
  EXPECT_TRUE(OpenSequence(root)->is_stereo());
  fs::rename(root + "/000000_right.png", root + "/image_1/000000.png");
  for (int i = 0; i < 2; ++i) {
    fs::rename(root + "/image_1/" + FrameFileName(i, ".png"), root + "/image_1/" + FrameFileName(i, ".png", 10));
  }
  const auto renamed = OpenSequence(root);
  EXPECT_FALSE(renamed->is_stereo());
  EXPECT_NE(renamed->NotStereoReason().find("image_1/000000.png is missing"), std::string::npos)
      << renamed->NotStereoReason();
  fs::remove_all(root + "/image_1");
  EXPECT_NE(OpenSequence(root)->NotStereoReason().find("no image_1/ folder"), std::string::npos);
  WriteText(root + "/calib.txt", "P0: 100 0 8 0 0 100 4 0 0 0 1 0\n");
  EXPECT_NE(OpenSequence(root)->NotStereoReason().find("has no P1 line"), std::string::npos);
}

TEST(SequenceReader, ColourPairMatchesGreyIsOneRuleForBothLayouts) {
  using internal::ColourPairMatchesGrey;
  const std::vector<double> grey_left{700, 0, 30, 0, 0, 700, 20, 0, 0, 0, 1, 0};
  const std::vector<double> grey_right{700, 0, 30, -378, 0, 700, 20, 0, 0, 0, 1, 0};
  const std::vector<double> beside{700, 0, 30, 42, 0, 700, 20, 0, 0, 0, 1, 0};  // KITTI: 6 cm beside camera 0
  EXPECT_TRUE(ColourPairMatchesGrey(grey_left, &grey_right, grey_left, &grey_right));
  EXPECT_TRUE(ColourPairMatchesGrey(grey_left, &grey_right, grey_left, nullptr));  // no right colour camera
  EXPECT_TRUE(ColourPairMatchesGrey(grey_left, nullptr, grey_left, nullptr));
  EXPECT_FALSE(ColourPairMatchesGrey(grey_left, &grey_right, beside, &grey_right));  // left is another viewpoint
  EXPECT_FALSE(ColourPairMatchesGrey(grey_left, &grey_right, grey_left, &beside));   // right is another one
  EXPECT_FALSE(ColourPairMatchesGrey(grey_left, nullptr, grey_left, &grey_right));   // a right colour, no right grey
}

TEST(SequenceReader, KittiColourCamerasBesideTheGreyOnesAreAnotherPair) {
  // image_0..3 as in a full KITTI odometry download: the grey pair by default, without the colour images
  // (another viewpoint), and the colour pair with its own calibration on request.
  const std::string root = MakeKittiSequence("kitti_four", 2, 60, 40);
  WriteText(root + "/calib.txt", kCalibColourBeside);
  fs::create_directories(root + "/image_2");
  fs::create_directories(root + "/image_3");
  for (int i = 0; i < 2; ++i) {
    cv::Mat colour;
    cv::cvtColor(RandomImage(60, 40, 200 + i), colour, cv::COLOR_GRAY2BGR);
    cv::imwrite(root + "/image_2/" + FrameFileName(i, ".png"), colour);
    cv::imwrite(root + "/image_3/" + FrameFileName(i, ".png"), colour);
  }
  SequenceReadOptions with_colour;
  with_colour.load_color = true;
  const auto grey = OpenSequence(root);
  EXPECT_NEAR(grey->camera().baseline, 0.54, 1e-12);
  EXPECT_FALSE(grey->has_color());
  EXPECT_TRUE(grey->Read(1, with_colour).left_color.empty());
  EXPECT_EQ(cv::norm(grey->Read(1).left, RandomImage(60, 40, 1), cv::NORM_INF), 0.0);
  const auto colour = OpenSequence(root, "", CameraPair::kColour);
  EXPECT_NEAR(colour->camera().baseline, 0.53, 1e-12);
  EXPECT_TRUE(colour->has_color());
  const StereoFrame f = colour->Read(1, with_colour);
  EXPECT_EQ(cv::norm(f.left, RandomImage(60, 40, 201), cv::NORM_INF), 0.0);
  EXPECT_EQ(f.left_color.type(), CV_8UC3);
  // A colour-only download (no image_0/image_1) is read as the colour pair with P2/P3.
  fs::remove_all(root + "/image_0");
  fs::remove_all(root + "/image_1");
  EXPECT_NEAR(OpenSequence(root)->camera().baseline, 0.53, 1e-12);
  // On a layout without a colour pair, colour is an error naming it.
  const std::string grey_only = MakeKittiSequence("kitti_grey_only", 1, 16, 8);
  EXPECT_THROW(OpenSequence(grey_only, "", CameraPair::kColour), Error);
}

TEST(SequenceReader, EurocIsRectifiedWithMetricBaseline) {
  const std::string root = TempDir("euroc");
  const int w = 64, h = 48;
  for (int c = 0; c < 2; ++c) {
    const std::string cam = root + "/mav0/cam" + std::to_string(c);
    fs::create_directories(cam + "/data");
    // cam1 is 0.11 m to the right of cam0, same orientation, no distortion.
    const double tx = c == 0 ? 0.0 : 0.11;
    WriteText(cam + "/sensor.yaml",
              "sensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [1, 0, 0, " + std::to_string(tx) +
                  ", 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\nrate_hz: 20\nresolution: [64, 48]\n"
                  "camera_model: pinhole\nintrinsics: [50.0, 50.0, 32.0, 24.0]\n"
                  "distortion_model: radial-tangential\ndistortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n");
    std::string csv = "#timestamp [ns],filename\n";
    // cam0 has a third frame that cam1 dropped: skipped in the pair, and said so.
    for (int i = 0; i < (c == 0 ? 3 : 2); ++i) {
      const std::string name = std::to_string(1000000000LL + i * 50000000LL) + ".png";
      cv::imwrite(cam + "/data/" + name, RandomImage(w, h, i + 10 * c));
      csv += std::to_string(1000000000LL + i * 50000000LL) + "," + name + "\n";
    }
    WriteText(cam + "/data.csv", csv);
  }
  ::testing::internal::CaptureStderr();
  auto seq = OpenSequence(root);
  const std::string warning = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(seq->size(), 2);
  EXPECT_NE(warning.find("1 cam0 frame(s) without a cam1 frame"), std::string::npos) << warning;
  EXPECT_NEAR(seq->camera().baseline, 0.11, 1e-6);
  EXPECT_NEAR(seq->timestamps()[1] - seq->timestamps()[0], 0.05, 1e-9);
  const StereoFrame f = seq->Read(0);
  EXPECT_EQ(f.left.size(), cv::Size(w, h));
  EXPECT_FALSE(f.right.empty());
  EXPECT_EQ(seq->FrameName(1), "1050000000");
  // cam0 alone: a monocular sequence (DVSO reads only the left camera).
  fs::remove_all(root + "/mav0/cam1");
  auto mono = OpenSequence(root);
  EXPECT_FALSE(mono->is_stereo());
  EXPECT_EQ(mono->size(), 3);
  EXPECT_NEAR(mono->camera().left.fx, 50.0, 1e-6);  // no distortion: the intrinsics stay
  EXPECT_DOUBLE_EQ(mono->camera().baseline, 0.0);
  const StereoFrame m = mono->Read(1);
  EXPECT_EQ(m.left.size(), cv::Size(w, h));
  EXPECT_TRUE(m.right.empty());
}

TEST(SequenceReader, MonocularFolderNeedsCameraFile) {
  const std::string root = TempDir("mono");
  for (int i = 0; i < 2; ++i) cv::imwrite(root + "/img" + std::to_string(i) + ".png", RandomImage(30, 20, i));
  EXPECT_THROW(OpenSequence(root), Error);
  const std::string camfile = TempDir("monocam") + "/camera.txt";
  WriteDsoCameraFile(camfile, PinholeCamera{40, 40, 15, 10, 30, 20});
  auto seq = OpenSequence(root, camfile);
  EXPECT_EQ(seq->size(), 2);
  EXPECT_FALSE(seq->is_stereo());
  EXPECT_TRUE(seq->Read(1).right.empty());
}

// Frames named without zero padding run in numeric order (text order put 10 before 2), and a camera
// file whose size the images do not have is an error at open (every frame was "unreadable" before).
TEST(SequenceReader, ImageFolderRunsInNumericOrderAndChecksTheCameraSize) {
  const std::string root = TempDir("natural_order");
  for (int i : {1, 2, 3, 10, 11}) cv::imwrite(root + "/" + std::to_string(i) + ".png", RandomImage(30, 20, i));
  const std::string camfile = TempDir("natural_order_cam") + "/camera.txt";
  WriteDsoCameraFile(camfile, PinholeCamera{40, 40, 15, 10, 30, 20});
  auto seq = OpenSequence(root, camfile);
  std::vector<std::string> names;
  for (int i = 0; i < seq->size(); ++i) names.push_back(seq->FrameName(i));
  EXPECT_EQ(names, (std::vector<std::string>{"1", "2", "3", "10", "11"}));
  WriteDsoCameraFile(camfile, PinholeCamera{80, 80, 30, 20, 60, 40});
  try {
    OpenSequence(root, camfile);
    ADD_FAILURE() << "a camera file of another size was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("30x20"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("camera.txt"), std::string::npos) << e.what();
  }
  // Natural order: numbers by value, zero-padded names as before, text elsewhere, a total order.
  using internal::NaturalLess;
  EXPECT_TRUE(NaturalLess("img2.png", "img10.png"));
  EXPECT_FALSE(NaturalLess("img10.png", "img2.png"));
  EXPECT_TRUE(NaturalLess("000009.png", "000010.png"));
  EXPECT_TRUE(NaturalLess("a1.png", "b0.png"));
  EXPECT_TRUE(NaturalLess("7.png", "007.png"));
  EXPECT_FALSE(NaturalLess("007.png", "7.png"));
  EXPECT_FALSE(NaturalLess("x.png", "x.png"));
  EXPECT_TRUE(NaturalLess("x", "x1"));
  // Numbered frames: the first missing number from 0 (times.txt's length counts), nothing for complete
  // lists or lists that are not one numbering.
  using internal::FirstMissingNumberedFrame;
  EXPECT_EQ(FirstMissingNumberedFrame({"d/000000.png", "d/000001.png", "d/000003.png"}), "d/000002.png");
  EXPECT_EQ(FirstMissingNumberedFrame({"d/000001.png", "d/000002.png"}), "d/000000.png");
  EXPECT_EQ(FirstMissingNumberedFrame({"d/000000.png", "d/000001.png"}, 4), "d/000002.png");
  EXPECT_EQ(FirstMissingNumberedFrame({"d/000000.png", "d/000001.png"}, 2), "");
  EXPECT_EQ(FirstMissingNumberedFrame({"d/000000.png", "d/000001.png"}), "");
  EXPECT_EQ(FirstMissingNumberedFrame({"d/a.png", "d/b.png"}), "");
  EXPECT_EQ(FirstMissingNumberedFrame({"d/1.png", "d/10.png"}), "");  // widths differ: not one numbering
  EXPECT_EQ(FirstMissingNumberedFrame({"d/000000000000.png", "d/999999999999.png"}), "d/000000000001.png");
  // A clip that kept its numbers, with a times.txt of its own length, counts from its first number.
  EXPECT_EQ(FirstMissingNumberedFrame({"d/001000.png", "d/001001.png"}, 2), "");
  EXPECT_EQ(FirstMissingNumberedFrame({"d/000001.png", "d/000002.png", "d/000004.png"}, 3), "d/000003.png");
  EXPECT_EQ(FirstMissingNumberedFrame({"d/000001.png", "d/000002.png"}, 3), "d/000000.png");
  // Timestamps as names: the digits after a decimal point are a fraction, not a number (.25 < .3).
  EXPECT_TRUE(NaturalLess("100.25.png", "100.3.png"));
  EXPECT_FALSE(NaturalLess("100.3.png", "100.25.png"));
  EXPECT_TRUE(NaturalLess("1317042130.175304.png", "1317042130.21173.png"));
  EXPECT_TRUE(NaturalLess("100.png", "100.25.png"));
  EXPECT_TRUE(NaturalLess("99.9.png", "100.png"));
  EXPECT_TRUE(NaturalLess("1.5.png", "1.50.png"));
  EXPECT_FALSE(NaturalLess("1.50.png", "1.5.png"));
  EXPECT_NE(NaturalLess("01.png", "1.0.png"), NaturalLess("1.0.png", "01.png"));  // equal as numbers, still ordered
}

TEST(YamlSection, StrictKeysAndNestedSections) {
  YamlSection s = YamlSection::FromString("points: 800\ntracker:\n  levels: 4\n", "cfg");
  int points = 2000, levels = 5;
  double unused = 1.0;
  s.Read("points", &points);
  s.Child("tracker").Read("levels", &levels);
  s.Read("absent", &unused);
  EXPECT_EQ(points, 800);
  EXPECT_EQ(levels, 4);
  EXPECT_EQ(unused, 1.0);
  EXPECT_NO_THROW(s.RequireAllKeysUsed());

  YamlSection typo = YamlSection::FromString("pionts: 800\ntracker:\n  lvls: 4\n", "cfg");
  typo.Read("points", &points);
  typo.Child("tracker").Read("levels", &levels);
  try {
    typo.RequireAllKeysUsed();
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pionts"), std::string::npos);
  }
  YamlSection nested = YamlSection::FromString("tracker:\n  lvls: 4\n", "cfg");
  nested.Child("tracker").Read("levels", &levels);
  EXPECT_THROW(nested.RequireAllKeysUsed(), Error);
  YamlSection wrong_type = YamlSection::FromString("points: many\n", "cfg");
  EXPECT_THROW(wrong_type.Read("points", &points), Error);
  // A key whose value was forgotten (or ~) is an error naming it, not a silent default.
  for (const char* text : {"points:\n", "points: ~\n", "tracker:\n  levels:\n"}) {
    YamlSection empty = YamlSection::FromString(text, "cfg");
    try {
      empty.Read("points", &points);
      empty.Child("tracker").Read("levels", &levels);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("has no value"), std::string::npos) << e.what();
    }
  }
}

// yaml-cpp keeps repeated keys and answers the first: `points` given twice loaded the first value, and
// a second `tracker:` section hid its keys from the unknown-key check.
TEST(YamlSection, RepeatedKeysAreErrorsAtAnyDepth) {
  for (const auto& [text, key] : std::vector<std::pair<std::string, std::string>>{
           {"points: 100\npoints: 3000\n", "'points'"},
           {"tracker:\n  levels: 4\ntracker:\n  bogus: 1\n", "'tracker'"},
           {"tracker:\n  levels: 4\n  levels: 5\n", "'tracker.levels'"},
           {"stages:\n  - name: a\n    name: b\n", "'stages[0].name'"}}) {
    try {
      YamlSection::FromString(text, "cfg");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("appears twice"), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(YamlSection::FromString("a:\n  x: 1\nb:\n  x: 2\n", "cfg"));  // same key in two maps
}

// yaml-cpp reads 0100 as octal 64 and 0x10 as 16: an integer option must be written in decimal.
TEST(YamlSection, IntegersAreDecimal) {
  int points = 0;
  for (const char* text : {"points: 0100\n", "points: 0x10\n", "points: -010\n"}) {
    YamlSection s = YamlSection::FromString(text, "cfg");
    EXPECT_THROW(s.Read("points", &points), Error) << text;
  }
  for (const auto& [text, value] : std::vector<std::pair<std::string, int>>{
           {"points: 0\n", 0}, {"points: 100\n", 100}, {"points: -7\n", -7}, {"points: +8\n", 8}}) {
    YamlSection s = YamlSection::FromString(text, "cfg");
    ASSERT_NO_THROW(s.Read("points", &points)) << text;
    EXPECT_EQ(points, value) << text;
  }
  double ratio = 0;  // floating-point values keep their leading zeros
  YamlSection s = YamlSection::FromString("ratio: 0.05\n", "cfg");
  s.Read("ratio", &ratio);
  EXPECT_DOUBLE_EQ(ratio, 0.05);
}
