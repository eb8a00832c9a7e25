// The world around an arm from the command line: clearances in a study's results whatever the threads,
// lanes and ranks; the clearance report of a grid; the viewer page of a study; a bad world key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tests/apps/cli_fixture.hpp"

namespace ff::test {
namespace {

// A pendulum swinging down past a post towards a floor (the link's end reaches 0.8 m below the hinge
// at q = 0.93; the floor is at -0.75), and a study moving the floor and the post.
const char* kRoom =
    "description: pendulum over a floor\n"
    "gravity: [0, 0, -9.81]\n"
    "bodies:\n"
    "  - name: arm\n"
    "    parent: base\n"
    "    mass: 2.0\n"
    "    com: [0.5, 0, 0]\n"
    "    inertia: {ixx: 0.001, iyy: 0.01, izz: 0.01}\n"
    "    joint: {axis: [0, 1, 0], armature: 0.05}\n"
    "tool: {body: arm, point: [0.5, 0, 0]}\n"
    "controller: {rate: 200}\n"
    "joints:\n"
    "  arm: {controller: {kp: 400, kd: 40, feedforward: 1, gravity_compensation: 1}}\n"
    "trajectory:\n"
    "  waypoints:\n"
    "    - {time: 1.0, joints: {arm: 1.0}}\n"
    "simulation: {settle: 0.5}\n"
    "world:\n"
    "  floor: {type: plane, position: [0, 0, -0.75]}\n"
    "  post: {type: cylinder, radius: 0.05, length: 2, position: [0.7, 0.2, 0]}\n"
    "collision:\n"
    "  arm: {radius: 0.04}\n";

const char* kRoomStudy =
    "name: room\n"
    "model: room.yaml\n"
    "seed: 3\n"
    "variables:\n"
    "  - path: world.floor.position[2]\n"
    "    distribution: {type: uniform, lower: -0.95, upper: -0.7}\n"
    "  - path: world.post.position[1]\n"
    "    distribution: {type: uniform, lower: 0.05, upper: 0.3}\n"
    "  - path: joints.arm.controller.kp\n"
    "    distribution: {type: uniform, lower: 200, upper: 600}\n"
    "design: {type: monte_carlo, samples: 12}\n"
    "specs: {contact: 0}\n";

class WorldCli : public CliFixture {
 public:
  WorldCli() : CliFixture("ff_world_cli_", {}) {}
  void SetUp() override {
    CliFixture::SetUp();
    write("room.yaml", kRoom);
    write("room_study.yaml", kRoomStudy);
  }
  // The cells of a CSV line (quoted cells may hold commas).
  static std::vector<std::string> cells(const std::string& line) {
    std::vector<std::string> out(1);
    bool quoted = false;
    for (char c : line) {
      if (c == '"') quoted = !quoted;
      else if (c == ',' && !quoted) out.emplace_back();
      else out.back() += c;
    }
    return out;
  }
  // A column of a results.csv by its header name.
  static std::vector<std::string> column(const std::string& csv, const std::string& name) {
    const auto lines = split_lines(csv);
    const std::vector<std::string> header = cells(lines.at(0));
    const auto at = static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
    EXPECT_LT(at, header.size()) << name;
    std::vector<std::string> out;
    for (std::size_t i = 1; i < lines.size(); ++i) out.push_back(cells(lines[i]).at(at));
    return out;
  }
};

TEST_F(WorldCli, ClearancesAreTheSameBitsWhateverTheThreadsAndLanes) {
  ASSERT_EQ(run("run room_study.yaml --out a --threads 1 --lanes 1").exit_code, 0);
  ASSERT_EQ(run("run room_study.yaml --out b --threads 2 --lanes 5").exit_code, 0);
  const std::string a = read_text(work / "a/results.csv"), b = read_text(work / "b/results.csv");
  EXPECT_EQ(a, b);
  // Some variants touch the floor, some do not: the columns are there and vary.
  const auto contact = column(a, "contact");
  EXPECT_NE(std::count(contact.begin(), contact.end(), "1"), 0);
  EXPECT_NE(std::count(contact.begin(), contact.end(), "0"), 0);
  for (const char* c : {"min_clearance_m", "min_clearance_time_s", "first_contact_s", "contacts", "arm_clearance_m",
                        "floor_clearance_m", "post_clearance_m"})
    EXPECT_EQ(column(a, c).size(), 12u) << c;
  // The Monte Carlo report gives P(contact) (the spec's miss) and the least clearance's statistics.
  const std::string md = read_text(work / "a/table.md");
  EXPECT_NE(md.find("| contact | 12 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| min_clearance_m | 12 |"), std::string::npos) << md;
  expect_png(work / "a/hist_clearance.png");
}

TEST_F(WorldCli, ClearancesAreTheSameBitsOnTwoMpiRanks) {
  ASSERT_TRUE(on_path("mpirun")) << "mpirun is missing: run scripts/bootstrap";
  ASSERT_EQ(run("run room_study.yaml --out a --threads 1 --lanes 1").exit_code, 0);
  const auto r = run_shell(mpirun(2) + quote(kBinary) + " run room_study.yaml --out c --threads 1 --lanes 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_text(work / "c/results.csv"), read_text(work / "a/results.csv"));
}

TEST_F(WorldCli, AGridStudyReportsTheLeastClearanceByItsParametersAndItsHeatMap) {
  write("grid.yaml",
        "name: grid\nmodel: room.yaml\nvariables:\n"
        "  - path: world.floor.position[2]\n    levels: [-0.9, -0.7]\n"
        "  - path: trajectory.waypoints[0].joints.arm\n    levels: [0.6, 1.0]\n"
        "design: {type: grid}\n");
  const auto r = run("run grid.yaml --out g");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string md = read_text(work / "g/table.md");
  EXPECT_NE(md.find("## Least clearance and contact by world.floor.position[2] and trajectory.waypoints[0].joints.arm"),
            std::string::npos)
      << md;
  expect_png(work / "g/heatmap_clearance.png");
  // The floor at -0.7 with the link's end reaching 0.84 m down: contact; at -0.9 with 0.6 rad: none.
  const std::string csv = read_text(work / "g/results.csv");
  EXPECT_EQ(column(csv, "contact"), (std::vector<std::string>{"0", "0", "0", "1"}));
}

TEST_F(WorldCli, TheViewerPageOfAStudyShowsTheVariantThatComesClosestSolidAndOthersAsGhosts) {
  ASSERT_EQ(run("run room_study.yaml --out a").exit_code, 0);
  const auto clearance = column(read_text(work / "a/results.csv"), "min_clearance_m");
  std::size_t worst = 0;
  for (std::size_t i = 1; i < clearance.size(); ++i)
    if (std::stod(clearance[i]) < std::stod(clearance[worst])) worst = i;
  // Every variant shown (11 ghosts): the one that comes closest of all is solid.
  const auto r = run("view room_study.yaml --out view.html --ghosts 11");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("variant " + std::to_string(worst) + ": "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("and 11 ghosts"), std::string::npos) << r.output;
  char least[64];
  std::snprintf(least, sizeof least, "least clearance %.4g m", std::stod(clearance[worst]));
  EXPECT_NE(r.output.find(least), std::string::npos) << least << " in " << r.output;
  const std::string page = read_text(work / "view.html");
  EXPECT_GT(page.size(), 500000u);  // three.js inlined
  EXPECT_NE(page.find("\"floor\""), std::string::npos);
  // The run's output directory: its study from results.sqlite, the variant with the least clearance in its
  // results solid without simulating the others; a study changed since the run is refused.
  const auto from_run = run("view a --out run.html --ghosts 0");
  ASSERT_EQ(from_run.exit_code, 0) << from_run.output;
  EXPECT_NE(from_run.output.find("variant " + std::to_string(worst) + ": "), std::string::npos) << from_run.output;
  EXPECT_NE(from_run.output.find(least), std::string::npos) << from_run.output;
  write("room_study.yaml", std::string(kRoomStudy) + "description: changed\n");
  // (run.yaml names the study by its absolute path, as flexfarm diff reads it.)
  expect_one_error_line(run("view a --out changed.html"), (work / "room_study.yaml").string() + " has changed since the run in a");
  EXPECT_FALSE(fs::exists(work / "changed.html"));
  // One model: its run alone; --eval is for studies.
  const auto one = run("view room.yaml --out one.html --set world.floor.position=[0,0,-0.7]");
  ASSERT_EQ(one.exit_code, 0) << one.output;
  EXPECT_NE(one.output.find("room.yaml solid, 301 samples, 1 capsules, 2 obstacles"), std::string::npos) << one.output;
  EXPECT_NE(run("view room.yaml --out x.html --eval 1").exit_code, 0);
}

// `simulate` of an arm with a world plots its least clearance against time (issue 32, item 23).
TEST_F(WorldCli, SimulateWithAWorldPlotsTheClearanceAgainstTime) {
  const auto r = run("simulate room.yaml --out s");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(", clearance.png}"), std::string::npos) << r.output;
  expect_png(work / "s/clearance.png");
  expect_png(work / "s/joints.png");
}

TEST_F(WorldCli, ABadObstacleIsOneLineNamingItsKeyAndWritesNothing) {
  std::string text = kRoom;
  text.replace(text.find("radius: 0.05, length: 2"), 23, "radius: 0.05");
  write("room.yaml", text);
  expect_one_error_line(run("simulate room.yaml --out out"), "room.yaml:20: world.post.length: missing: a cylinder needs it");
  expect_one_error_line(run("view room_study.yaml --out v.html"), "room.yaml:20: world.post.length: missing");
  EXPECT_FALSE(fs::exists(work / "out"));
  EXPECT_FALSE(fs::exists(work / "v.html"));
}

// The tank riser's safety study cut to one draw: the shoulder's encoder slips by 0.3 rad at 2 s.
class TankRiserCli : public CliFixture {
 protected:
  TankRiserCli()
      : CliFixture("ff_tank_riser_cli_", {{"configs/tank_riser.yaml", "configs/tank_riser.yaml"},
                                          {"configs/studies/tank_riser_safety.yaml", "safety.yaml"}}) {}
  void SetUp() override {
    CliFixture::SetUp();
    fs::create_directories(work / "configs/meshes");
    for (const char* m : {"dome.stl", "pump.stl"})
      fs::copy_file(kSource + "/configs/meshes/" + m, work / "configs/meshes" / m);
  }
};

TEST_F(TankRiserCli, AGuardAt10CmStopsTheArmThatTouchesTheRiserWithoutOne) {
  // The study's three cases over one grid point instead of its Monte Carlo draws.
  std::string study = read_text(work / "safety.yaml");
  study.replace(study.find("model: ../tank_riser.yaml"), 25, "model: configs/tank_riser.yaml");
  study = study.substr(0, study.find("variables:")) +
          "variables:\n"
          "  - path: joints.shoulder.sensors.angle.fault_offset\n    levels: [0.3]\n"
          "  - path: joints.shoulder.sensors.angle.fault_time\n    levels: [2.0]\n"
          "design: {type: grid}\nspecs: {contact: 0}\n";
  write("safety.yaml", study);
  const auto r = run("run safety.yaml --out s");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string csv = read_text(work / "s/results.csv");
  // No guard (it only records, at 10 cm): the leaning arm touches; a stop at 5 cm comes too late; at 10 cm
  // it stops the arm short of the riser, 4 mm from it.
  EXPECT_EQ(WorldCli::column(csv, "contact"), (std::vector<std::string>{"1", "1", "0"}));
  const auto trip = WorldCli::column(csv, "guard_trip_s");
  ASSERT_EQ(trip.size(), 3u);
  EXPECT_EQ(trip[0], trip[2]);  // the recording guard trips when the stopping one does
  EXPECT_GT(std::stod(trip[2]), 2.0);
  EXPECT_LT(std::stod(trip[2]), 2.3);
  EXPECT_LT(std::stod(WorldCli::column(csv, "min_clearance_m")[0]), 0.0);
  EXPECT_GT(std::stod(WorldCli::column(csv, "min_clearance_m")[2]), 0.002);
  EXPECT_GT(std::stod(WorldCli::column(csv, "stopping_distance_m")[2]), 0.1);
}

}  // namespace
}  // namespace ff::test
