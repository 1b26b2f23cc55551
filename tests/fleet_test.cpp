// lmcal fleet: finding the sets, refusing bad layouts before any work, and a generated fleet
// end to end — the population's spread recovered within its interval, the planted outliers,
// the drifting unit and the corrupt set named and nothing else, the same bytes with any
// number of jobs or shards, and a second run that recomputes nothing.
#include "lmcal/fleet/fleet.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "lmcal/error.hpp"
#include "lmcal/fleet/fleet_summary.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/rig/fleet_rig.hpp"
#include "support/temp_folder.hpp"

namespace lmcal {
namespace {

namespace fs = std::filesystem;

class FleetTest : public test::TempFolderTest {
 protected:
  // A minimal measurement set: one friction log (its content is not read by discovery).
  void set(const std::string& folder) { write(fs::path("root") / folder / "friction.csv", "time_s\n"); }
  fs::path root() const { return dir_ / "root"; }

  // discover_fleet's InputError text, or "" when it accepts.
  std::string refusal() const {
    try {
      discover_fleet(root());
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(FleetTest, FoldersNameTheUnitAndADateFolderTheDate) {
  set("u17/2026-09-01");
  set("u17/2026-09-08");
  set("lot3/g5");
  write("root/u17/notes/readme.txt", "not a set");
  const Fleet f = discover_fleet(root());
  ASSERT_EQ(f.sets.size(), 3u);
  EXPECT_EQ(f.source, "folders");
  EXPECT_EQ(f.sets[0].id, "lot3/g5");
  EXPECT_EQ(f.sets[0].unit, "lot3/g5");
  EXPECT_EQ(f.sets[0].date, "");
  EXPECT_EQ(f.sets[1].id, "u17/2026-09-01");
  EXPECT_EQ(f.sets[1].unit, "u17");
  EXPECT_EQ(f.sets[1].date, "2026-09-01");
  EXPECT_EQ(f.sets[2].date, "2026-09-08");
}

TEST_F(FleetTest, AFleetFileNamesUnitAxisMachineAndDate) {
  set("a");
  set("b");
  write("root/fleet.toml",
        "[[set]]\nfolder = \"b\"\nunit = \"17\"\naxis = \"X\"\nmachine = \"M3\"\ndate = 2026-09-01\n"
        "[[set]]\nfolder = \"a\"\nunit = \"17\"\naxis = \"X\"\ndate = \"2026-10-01\"\n");
  const Fleet f = discover_fleet(root());
  ASSERT_EQ(f.sets.size(), 2u);
  EXPECT_EQ(f.source, "fleet.toml");
  EXPECT_EQ(f.sets[0].id, "a");
  EXPECT_EQ(f.sets[0].date, "2026-10-01");
  EXPECT_EQ(f.sets[1].series(), "17 axis X");
  EXPECT_EQ(f.sets[1].machine, "M3");
}

TEST_F(FleetTest, BadLayoutsAreRefusedBeforeAnyWorkNamingTheEntry) {
  fs::create_directories(root() / "empty");
  EXPECT_NE(refusal().find("no measurement folders"), std::string::npos) << refusal();

  set("a");
  write("root/fleet.toml", "[[set]]\nfolder = \"a\"\n\n[[set]]\nfolder = \"missing\"\n");
  EXPECT_NE(refusal().find("fleet.toml:5:10: folder "), std::string::npos) << refusal();
  EXPECT_NE(refusal().find("does not exist"), std::string::npos) << refusal();

  set("b");
  write("root/fleet.toml", "[[set]]\nfolder = \"a\"\nunit = \"7\"\ndate = 2026-09-01\n"
                           "[[set]]\nfolder = \"b\"\nunit = \"7\"\ndate = 2026-09-01\n");
  EXPECT_NE(refusal().find("unit 7 has two sets dated '2026-09-01' (a and b)"), std::string::npos) << refusal();

  write("root/fleet.toml", "[[set]]\nfolder = \"a\"\n[[set]]\nfolder = \"a/\"\n");
  EXPECT_NE(refusal().find("listed twice"), std::string::npos) << refusal();

  write("root/fleet.toml", "[[set]]\nfolder = \"a\"\ndate = \"2026-02-30\"\n");
  EXPECT_NE(refusal().find("fleet.toml:3:8: expected a date"), std::string::npos) << refusal();

  write("root/fleet.toml", "[[set]]\nfolder = \"a\"\nshift = 2\n");
  EXPECT_NE(refusal().find("fleet.toml:3:1: unknown key 'shift'"), std::string::npos) << refusal();

  fs::create_directories(root() / "c");
  write("root/fleet.toml", "[[set]]\nfolder = \"c\"\n");
  EXPECT_NE(refusal().find("holds no measurements"), std::string::npos) << refusal();
}

TEST_F(FleetTest, EveryFolderStaysInsideTheRootUnlessAllowed) {
  set("a");
  write("B/unit/friction.csv", "time_s\n");  // a sibling fleet's set
  auto fleet_file = [&](const std::string& folder) { write("root/fleet.toml", "[[set]]\nfolder = \"" + folder + "\"\n"); };
  fleet_file("../B/unit");
  EXPECT_NE(refusal().find("fleet.toml:2:10: folder '../B/unit' is outside"), std::string::npos) << refusal();
  fleet_file((dir_ / "B/unit").string());
  EXPECT_NE(refusal().find("fleet.toml:2:10: folder '/"), std::string::npos) << refusal();
  EXPECT_NE(refusal().find("is outside"), std::string::npos) << refusal();
  // No oracle: a folder outside that does not exist is refused with the same words.
  fleet_file("../B/missing");
  EXPECT_NE(refusal().find("folder '../B/missing' is outside"), std::string::npos) << refusal();
  fs::create_directory_symlink(dir_ / "B/unit", root() / "link");
  fleet_file("link");
  EXPECT_NE(refusal().find("is outside"), std::string::npos) << refusal();
  EXPECT_NE(refusal().find("through a symbolic link"), std::string::npos) << refusal();
  fs::remove(root() / "fleet.toml");
  EXPECT_NE(refusal().find("link: this folder is outside"), std::string::npos) << "the walk too: " << refusal();

  // Allowed: read, but named so that its outputs stay under OUT.
  fleet_file("../B/unit");
  const Fleet fleet = discover_fleet(root(), {}, true);
  ASSERT_EQ(fleet.sets.size(), 1u);
  EXPECT_EQ(fleet.sets[0].id, "outside" + fs::weakly_canonical(dir_ / "B/unit").generic_string());
}

TEST_F(FleetTest, LoopsLongNamesAndLinksToItselfAreRefusedNotThrown) {
  set("a");
  fs::create_symlink("loop", root() / "loop");           // a link to itself under ROOT
  fs::create_directory_symlink("..", root() / "a/up");  // a loop back up
  EXPECT_EQ(refusal(), "") << "links that lead nowhere or back are not followed";
  EXPECT_EQ(discover_fleet(root()).sets.size(), 1u);
  write("root/fleet.toml", "[[set]]\nfolder = \"a/" + std::string(300, 'x') + "\"\n");
  EXPECT_NE(refusal().find("fleet.toml:2:10: folder 'a/xxx"), std::string::npos) << refusal();
  fs::remove(root() / "fleet.toml");
  fs::create_symlink("fleet.toml", root() / "fleet.toml");
  EXPECT_NE(refusal().find("Too many levels of symbolic links"), std::string::npos) << refusal();
  fs::remove(root() / "fleet.toml");
  write("root/b\x1b]0;pwned\x07/friction.csv", "time_s\n");
  EXPECT_NE(refusal().find("control character"), std::string::npos) << "a folder name with an escape: " << refusal();
}

// Causes across the fleet: units whose diagnosis accepted each, at any date; a failed set
// counts for nothing. Records made by hand, so no calibration runs.
TEST(FleetSummary, CountsTheUnitsShowingEachCause) {
  Fleet fleet{.root = "plant", .source = "folders"};
  std::vector<std::string> records;
  auto add = [&](std::string unit, std::string date, std::vector<std::string> causes, std::string status = "ok") {
    FleetSet s{.id = unit + "/" + date, .unit = unit, .date = date};
    FleetRecord r{.id = s.id, .unit = s.unit, .date = s.date, .status = status, .friction_causes = std::move(causes)};
    r.parameters.push_back({.model = "friction", .name = "mu_v", .unit = "1", .value = 0.003, .se = 1e-4});
    records.push_back(fleet_record_json(r));
    fleet.sets.push_back(std::move(s));
  };
  add("a", "2026-09-01", {"seal_drag"});
  add("a", "2026-09-08", {"seal_drag", "viscous_load"});
  add("b", "2026-09-01", {});
  add("b", "2026-09-08", {"seal_drag"});
  add("c", "2026-09-01", {"viscous_load"}, "failed");
  add("d", "2026-09-01", {});
  const FleetSummary s = summarize_fleet(fleet, records);
  ASSERT_EQ(s.causes.size(), 1u + 1u);
  EXPECT_EQ(s.causes[0].cause, "seal_drag");
  EXPECT_EQ(s.causes[0].series, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(s.causes[1].cause, "viscous_load");
  EXPECT_EQ(s.causes[1].series, (std::vector<std::string>{"a"}));
  EXPECT_EQ(s.units, 4u);
  EXPECT_EQ(s.failed, 1u);
  // Three units estimated mu_v (c failed): a population, each unit by its earliest set.
  EXPECT_EQ(s.population.at(0).series, (std::vector<std::string>{"a", "b", "d"}));
  EXPECT_EQ(s.population.at(0).set_ids.front(), "a/2026-09-01");
}

// --- a generated fleet, end to end ---------------------------------------------------------------

class GeneratedFleet : public test::TempFolderTest {
 protected:
  static FleetRigConfig config() {
    FleetRigConfig c;  // 40 units, 4 of them on 8 dates; spreads of mu_v 8 %, mu_st 5 %, alpha 5 %
    c.outliers = {{9, "mu_st", 1.4}, {21, "mu_v", 1.5}};
    c.drifts = {{2, "mu_v", 0.25}};
    c.corrupt = {30};
    return c;
  }
  void SetUp() override {
    TempFolderTest::SetUp();
    OutputSet out;
    for (const auto& [file, text] : generate_fleet(config()).files) out.add(dir_ / "fleet" / file, text);
    out.commit();
    fleet_ = discover_fleet(dir_ / "fleet");
  }
  FleetOptions options(const std::string& out, std::size_t jobs, std::size_t shard = 0, std::size_t shards = 1) const {
    FleetOptions o;
    o.output_dir = dir_ / out;
    o.jobs = jobs;
    o.shard = shard;
    o.shards = shards;
    return o;
  }
  static std::vector<std::string> all(const FleetRun& run) {
    std::vector<std::string> records;
    for (const auto& r : run.records) records.push_back(r.value());
    return records;
  }
  static std::string summary_bytes(const FleetSummary& s) {
    std::string bytes;
    for (const auto& [name, text] : fleet_summary_outputs(s)) bytes += name + "\n" + text;
    return bytes;
  }
  Fleet fleet_;
};

TEST_F(GeneratedFleet, ThePopulationTheOutliersTheDriftAndTheCorruptSetAreFound) {
  ASSERT_EQ(fleet_.sets.size(), 36u + 4u * 8u);
  const FleetRun run = run_fleet(fleet_, options("out", 2));
  EXPECT_EQ(run.computed, fleet_.sets.size());
  EXPECT_EQ(run.failed, 1u);
  const FleetSummary s = summarize_fleet(fleet_, all(run));
  EXPECT_EQ(s.units, 40u);

  // The corrupt set, and only it, failed, with the file and line in its error.
  ASSERT_EQ(s.failed, 1u);
  const auto failed = std::find_if(s.records.begin(), s.records.end(), [](const FleetRecord& r) { return r.status != "ok"; });
  EXPECT_EQ(failed->id, "u30");
  EXPECT_NE(failed->error.find("u30/friction.csv:"), std::string::npos) << failed->error;

  // The planted outliers and nothing else.
  std::set<std::string> outliers;
  for (const auto& o : s.outliers) outliers.insert(o.series + " " + o.parameter);
  EXPECT_EQ(outliers, (std::set<std::string>{"u09 mu_st", "u21 mu_v"}));

  // The drifting unit and nothing else; its change near the planted +25 %.
  std::vector<const DriftFinding*> drifting;
  for (const auto& d : s.drift)
    if (d.significant) drifting.push_back(&d);
  ASSERT_EQ(drifting.size(), 1u);
  EXPECT_EQ(drifting[0]->series + " " + drifting[0]->parameter, "u02 mu_v");
  EXPECT_NEAR(drifting[0]->drift.trend_percent, 25, 8);
  EXPECT_GT(s.drift.size(), 20u);  // every dated unit's constants were tested

  // The between-unit SD of each spread constant recovered within its interval.
  const FleetRigConfig c = config();
  const FrictionConstants<double> paper = c.friction.constants;
  const std::vector<std::pair<std::string, double>> truth = {
      {"mu_v", c.spread.at("mu_v") * paper.mu_v}, {"mu_st", c.spread.at("mu_st") * paper.mu_st},
      {"alpha", c.spread.at("alpha") * c.thermal_rig.alpha}};
  for (const auto& [name, sd] : truth) {
    const auto pop = std::find_if(s.population.begin(), s.population.end(), [&](const auto& p) { return p.name == name; });
    ASSERT_NE(pop, s.population.end()) << name;
    const RandomEffects& r = pop->fit.population;
    EXPECT_GE(r.k, 38u) << name;
    EXPECT_LE(r.tau_low, sd) << name;
    EXPECT_GE(r.tau_high, sd) << name;
    EXPECT_GT(r.i2, 0.8) << name << ": the spread is real, not estimation noise";
  }
}

TEST_F(GeneratedFleet, AnyJobsOrShardsGiveTheSameBytesAndASecondRunRecomputesNothing) {
  const std::string two_jobs = summary_bytes(summarize_fleet(fleet_, all(run_fleet(fleet_, options("a", 2)))));
  const std::string one_job = summary_bytes(summarize_fleet(fleet_, all(run_fleet(fleet_, options("b", 1)))));
  EXPECT_EQ(two_jobs, one_job);

  // Shards: each its share, the summary from the records on disk.
  const FleetRun first = run_fleet(fleet_, options("c", 2, 0, 2));
  EXPECT_EQ(first.computed, (fleet_.sets.size() + 1) / 2);
  EXPECT_THROW(read_fleet_records(fleet_, options("c", 1)), InputError);  // shard 1 missing
  run_fleet(fleet_, options("c", 2, 1, 2));
  EXPECT_EQ(summary_bytes(summarize_fleet(fleet_, read_fleet_records(fleet_, options("c", 1)))), two_jobs);

  // Again: nothing recomputed, the same summary.
  const FleetRun again = run_fleet(fleet_, options("a", 2));
  EXPECT_EQ(again.computed, 0u);
  EXPECT_EQ(again.skipped, fleet_.sets.size());
  EXPECT_EQ(summary_bytes(summarize_fleet(fleet_, all(again))), two_jobs);

  // A changed input, or changed options, make that set (or all) again.
  { std::ofstream(dir_ / "fleet/u05/friction.csv", std::ios::app) << "# a comment added\n"; }
  EXPECT_EQ(run_fleet(fleet_, options("a", 2)).computed, 1u);
  FleetOptions other = options("a", 2);
  other.calibration.diagnose = false;
  EXPECT_NE(fleet_options_hash(other.calibration), fleet_options_hash(options("a", 2).calibration));
  EXPECT_FALSE(up_to_date_record(fleet_, 0, other, fleet_options_hash(other.calibration)));
}

}  // namespace
}  // namespace lmcal
