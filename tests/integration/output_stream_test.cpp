// The streamed outputs (loop/outputs/output_stream.hpp) under a full disk, a writer that cannot
// keep up, and back-pressure on the simulated clock: what is lost is counted, the frame thread
// never blocks in real time, and the files that are written stay valid (read back with the
// project's candump reader and nlohmann::json, independent of the writer's formatting code).

#include "loop/outputs/output_stream.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "io/candump.hpp"
#include "loop/scenario.hpp"

namespace loop = radar_emu::loop;
namespace fs = std::filesystem;
namespace icd = radar_emu::io::icd;

namespace {

fs::path temp_dir(const std::string& name) {
  // One directory per process: CTest runs each test of a suite as its own process, in parallel,
  // and the outputs are written while the run goes (a shared directory would be clobbered).
  const fs::path p =
      fs::temp_directory_path() / ("radar_emu_os_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

loop::Scenario scenario() {
  return loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>");
}

loop::OutputStreamConfig config(const fs::path& dir, const loop::Scenario& s) {
  loop::OutputStreamConfig c;
  c.dir = dir;
  c.scenario = &s;
  c.frames_planned = 100;
  c.object_names = {"ground", "tower \"A\"", "truck"};  // a name that needs escaping
  c.truth_objects = {1, 2};
  c.max_detections = 8;
  c.bus_frames_per_frame = 40;
  return c;
}

// Frame k: 40 CAN FD frames in (64 bytes each: about 170 characters a candump line), one out,
// k % 4 detections of object 1 (the last one clutter), one object in view.
struct Feeder {
  std::vector<icd::Detection> dets = std::vector<icd::Detection>(8);
  std::vector<radar_emu::radar::Detection> sensor = std::vector<radar_emu::radar::Detection>(8);
  std::array<loop::ObjectTruth, 1> truth{};

  void frame(loop::OutputStream& out, std::uint64_t k) {
    radar_emu::io::CanFrame f;
    f.fd = true;
    f.len = 64;
    f.id = 0x123;
    for (std::size_t i = 0; i < f.data.size(); ++i)
      f.data[i] = static_cast<std::uint8_t>(k + i);
    for (int i = 0; i < 40; ++i) {
      f.timestamp_ns = 1'767'225'600'000'000'000LL + static_cast<std::int64_t>(k) * 50'000'000 + i;
      out.bus_in(f);
    }
    f.fd = false;
    f.len = 8;
    f.id = 0x708;
    out.bus_out(f);
    const std::size_t n = k % 4;
    for (std::size_t i = 0; i < n; ++i) {
      dets[i].range_m = 1000.0 + static_cast<double>(k);
      dets[i].snr_db = 20.0;
      sensor[i].object_id = i + 1 == n ? radar_emu::radar::kNoObject : std::uint32_t{1};
    }
    truth[0].object_id = 2;
    truth[0].range_m = 1500.0;
    loop::FrameRecord rec;
    rec.frame_index = k;
    rec.time_s = static_cast<double>(k) * 0.05;
    rec.header.frame_counter = static_cast<std::uint16_t>(k);
    rec.ownship_valid = true;
    std::array<std::int64_t, radar_emu::timing::kStageCount> ns{};
    ns.fill(1'500'000);
    out.frame(rec, ns, std::span(dets.data(), n), std::span(sensor.data(), n), truth);
  }
};

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

std::size_t lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::size_t n = 0;
  std::string line;
  while (std::getline(in, line))
    ++n;
  return n;
}

}  // namespace

TEST(OutputStream, EveryFrameIsWrittenAndReadsBack) {
  const loop::Scenario s = scenario();
  const fs::path dir = temp_dir("all");
  loop::OutputStream out(config(dir, s));
  Feeder feed;
  for (std::uint64_t k = 0; k < 100; ++k)
    feed.frame(out, k);
  const loop::OutputCounters c = out.finish();
  EXPECT_TRUE(c.complete());
  EXPECT_EQ(c.frames_written, 100u);
  EXPECT_EQ(c.bus_frames_written, 100u * 41u);
  // The candump logs read back with the project's parser (python-can reads them in the CLI tests).
  const auto in = radar_emu::io::read_candump_file(dir / "bus_in.log");
  ASSERT_EQ(in.size(), 4000u);
  EXPECT_TRUE(in[41].frame.fd);
  EXPECT_EQ(in[41].frame.len, 64u);
  EXPECT_EQ(in[41].frame.data[3], 1u + 3u);  // frame 1, byte 3
  EXPECT_EQ(radar_emu::io::read_candump_file(dir / "bus_out.log").size(), 100u);
  const nlohmann::json d = read_json(dir / "detections.json");
  ASSERT_EQ(d.at("frames").size(), 100u);
  EXPECT_EQ(d.at("frames_dropped"), 0);
  const auto& f7 = d.at("frames")[7];  // 7 % 4 = 3 detections, the last one clutter
  EXPECT_EQ(f7.at("frame_counter"), 7);
  EXPECT_DOUBLE_EQ(f7.at("time_s").get<double>(), 0.35);
  ASSERT_EQ(f7.at("detections").size(), 3u);
  EXPECT_DOUBLE_EQ(f7.at("detections")[0].at("range_m").get<double>(), 1007.0);
  EXPECT_EQ(f7.at("detections")[0].at("object"), "tower \"A\"");
  EXPECT_TRUE(f7.at("detections")[2].at("object_id").is_null());
  EXPECT_EQ(f7.at("detections")[2].at("object"), "clutter");
  const nlohmann::json t = read_json(dir / "truth.json");
  ASSERT_EQ(t.at("frames").size(), 100u);
  EXPECT_EQ(t.at("objects").size(), 2u);
  EXPECT_EQ(t.at("frames")[3].at("objects")[0].at("object"), "truck");
  EXPECT_EQ(lines_of(dir / "frames.csv"), 101u);
  EXPECT_TRUE(fs::exists(dir / "detections.png"));
  fs::remove_all(dir);
}

TEST(OutputStream, AFullDiskIsCountedPerFileAndTheOtherFilesStayValid) {
  // bus_out.log is /dev/full: every write fails with ENOSPC.
  const loop::Scenario s = scenario();
  const fs::path dir = temp_dir("full");
  fs::create_symlink("/dev/full", dir / "bus_out.log");
  loop::OutputStream out(config(dir, s));
  Feeder feed;
  for (std::uint64_t k = 0; k < 50; ++k)
    feed.frame(out, k);
  const loop::OutputCounters c = out.finish();
  EXPECT_FALSE(c.complete());
  EXPECT_EQ(c.frames_written, 50u);
  for (const loop::OutputFileCounters& f : c.files) {
    if (f.name == "bus_out.log") {
      EXPECT_GT(f.write_errors, 0u);
      EXPECT_GT(f.bytes_lost, 0u);
      EXPECT_EQ(f.bytes_written, 0u);
      EXPECT_NE(f.first_error.find("No space"), std::string::npos) << f.first_error;
    } else {
      EXPECT_EQ(f.write_errors, 0u) << f.name;
    }
  }
  EXPECT_EQ(read_json(dir / "detections.json").at("frames").size(), 50u);
  EXPECT_EQ(radar_emu::io::read_candump_file(dir / "bus_in.log").size(), 2000u);
  fs::remove_all(dir);
}

TEST(OutputStream, AStalledWriterMakesARealTimeProducerDropNotWait) {
  // bus_in.log is a pipe nobody reads: once its 64 KiB are full, the writer thread blocks in
  // write(). The producer (real-time policy) must carry on: every call returns, what the rings
  // cannot hold is dropped and counted. A producer that waited would never return, since the
  // pipe is drained only after the last frame.
  const loop::Scenario s = scenario();
  const fs::path dir = temp_dir("stall");
  const fs::path fifo = dir / "bus_in.log";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const int reader = open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  loop::OutputStreamConfig c = config(dir, s);
  c.wait_when_full = false;
  c.slack_frames = 4;
  std::uint64_t frames_dropped = 0, bus_dropped = 0;
  loop::OutputCounters counters;
  {
    loop::OutputStream out(std::move(c));
    Feeder feed;
    constexpr std::uint64_t kFrames = 400;  // 400 x 40 lines of about 170 bytes: 2.7 MB
    for (std::uint64_t k = 0; k < kFrames; ++k) {
      feed.frame(out, k);
      if (k % 50 == 0)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));  // let the writer block
    }
    bus_dropped = out.bus_frames_dropped();
    // Unblock the writer: drain the pipe until finish() closes it.
    std::thread drain([reader] {
      fcntl(reader, F_SETFL, 0);  // blocking reads from here on
      std::array<char, 65536> buf{};
      while (read(reader, buf.data(), buf.size()) > 0) {
      }
    });
    counters = out.finish();
    drain.join();
    frames_dropped = counters.frames_dropped;
    EXPECT_EQ(counters.frames_written + counters.frames_dropped, kFrames);
    EXPECT_EQ(counters.bus_frames_written + counters.bus_frames_dropped, kFrames * 41);
  }
  close(reader);
  std::printf("  stalled writer: %llu frames and %llu bus frames dropped\n",
              static_cast<unsigned long long>(frames_dropped),
              static_cast<unsigned long long>(bus_dropped));
  EXPECT_GT(bus_dropped, 0u);
  EXPECT_GT(frames_dropped, 0u);
  EXPECT_FALSE(counters.complete());
  // What was written is still a valid document, and says how many frames it lacks.
  const nlohmann::json d = read_json(dir / "detections.json");
  EXPECT_EQ(d.at("frames").size(), counters.frames_written);
  EXPECT_EQ(d.at("frames_dropped").get<std::uint64_t>(), frames_dropped);
  fs::remove_all(dir);
}

TEST(OutputStream, OnTheSimulatedClockTheProducerWaitsAndNothingIsLost) {
  // Rings of two frames and a producer far faster than the writer (which sleeps 2 ms when idle):
  // the producer waits, counted, and every frame reaches the files.
  const loop::Scenario s = scenario();
  const fs::path dir = temp_dir("wait");
  loop::OutputStreamConfig c = config(dir, s);
  c.slack_frames = 2;
  loop::OutputStream out(std::move(c));
  Feeder feed;
  for (std::uint64_t k = 0; k < 300; ++k) {
    out.wait_for_room();
    feed.frame(out, k);
  }
  const loop::OutputCounters counters = out.finish();
  EXPECT_TRUE(counters.complete());
  EXPECT_GT(counters.waits, 0u);
  EXPECT_EQ(counters.frames_written, 300u);
  EXPECT_EQ(radar_emu::io::read_candump_file(dir / "bus_in.log").size(), 300u * 40u);
  const nlohmann::json d = read_json(dir / "detections.json");
  ASSERT_EQ(d.at("frames").size(), 300u);
  for (std::size_t k = 0; k < 300; ++k)
    ASSERT_EQ(d.at("frames")[k].at("frame_counter").get<std::size_t>(), k);
  fs::remove_all(dir);
}

TEST(OutputStream, AnOutputDirectoryThatCannotBeMadeFailsAtSetupWithItsPath) {
  const loop::Scenario s = scenario();
  const fs::path dir = temp_dir("bad");
  std::ofstream(dir / "file") << "x";
  try {
    loop::OutputStream out(config(dir / "file" / "out", s));
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("file/out"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}
