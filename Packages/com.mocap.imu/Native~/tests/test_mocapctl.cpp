// The command-line tool as a user runs it: synth -> replay with the truth, and record from a
// pseudo-terminal. Output is parsed, so a change that breaks what users read breaks here too.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include "../tools/mocapctl/options.h"
#include "e2e_support.h"
#include "test_support.h"

extern "C" {
#include "capture_file.h"
}

namespace {

CommandResult run_command(const std::string &args)
{
    return run_shell(std::string(MOCAP_MOCAPCTL) + " " + args);
}

}  // namespace

TEST(Mocapctl, SynthThenReplayCalibratesAndReportsSmallError)
{
    std::string dir = test_temp_dir();
    CommandResult synth = run_command("synth --out " + dir + "/c.cap --truth " + dir +
                                      "/t.csv --motion walk --world enu --seed 3");
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    CommandResult replay = run_command("replay " + dir + "/c.cap --truth " + dir + "/t.csv --save-calibration " +
                                       dir + "/c.calibration --csv " + dir + "/frames.csv");
    ASSERT_EQ(replay.exit_code, 0) << replay.output;
    EXPECT_NE(replay.output.find("heading step: accepted"), std::string::npos) << replay.output;
    EXPECT_NE(replay.output.find("T-pose step: accepted"), std::string::npos) << replay.output;
    std::smatch m;
    std::regex worst("worst sensor mean ([0-9.]+) deg");
    ASSERT_TRUE(std::regex_search(replay.output, m, worst)) << replay.output;
    EXPECT_LT(std::stod(m[1]), 1.0);  // realistic noise gives ~0.3 deg (see test_pipeline)

    // The saved calibration replays the capture without running the prelude steps again.
    CommandResult again = run_command("replay " + dir + "/c.cap --truth " + dir + "/t.csv --calibration " +
                                      dir + "/c.calibration");
    ASSERT_EQ(again.exit_code, 0) << again.output;
    ASSERT_TRUE(std::regex_search(again.output, m, worst)) << again.output;
    EXPECT_LT(std::stod(m[1]), 1.0);
    EXPECT_EQ(again.output.find("heading step"), std::string::npos);

    // One CSV row per output frame, 51 columns (3 + 6 sensors x 8).
    auto csv = read_file_bytes(dir + "/frames.csv");
    std::string text(csv.begin(), csv.end());
    size_t rows = std::count(text.begin(), text.end(), '\n');
    EXPECT_GT(rows, 600u);
    std::string header = text.substr(0, text.find('\n'));
    EXPECT_EQ(std::count(header.begin(), header.end(), ','), 50);
}

// `--sensors` with a chest on node 6: synth writes seven nodes and a truth of seven column
// groups; replay with the same set calibrates all seven and measures the chest against its truth;
// the saved calibration lists the seven segments.
TEST(Mocapctl, SevenSensorSynthAndReplay)
{
    std::string dir = test_temp_dir();
    const std::string set = "pelvis=0,left_wrist=1,right_wrist=2,left_shin=3,right_shin=4,head=5,chest=6";
    CommandResult synth = run_command("synth --out " + dir + "/c.cap --truth " + dir + "/t.csv --motion walk --seed 5 " +
                                      "--sensors " + set);
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    EXPECT_NE(synth.output.find("7 sensors (" + set + ")"), std::string::npos) << synth.output;
    auto truth = read_file_bytes(dir + "/t.csv");
    std::string truth_text(truth.begin(), truth.end());
    std::string truth_header = truth_text.substr(0, truth_text.find('\n'));
    EXPECT_EQ(std::count(truth_header.begin(), truth_header.end(), ','), 1 + 7 * 7) << truth_header;
    EXPECT_NE(truth_header.find(",chest_qw,"), std::string::npos) << truth_header;

    CommandResult replay = run_command("replay " + dir + "/c.cap --truth " + dir + "/t.csv --sensors " + set +
                                       " --save-calibration " + dir + "/c.calibration --csv " + dir + "/f.csv");
    ASSERT_EQ(replay.exit_code, 0) << replay.output;
    EXPECT_NE(replay.output.find("T-pose step: accepted"), std::string::npos) << replay.output;
    std::smatch m;
    // The summary row of the chest: its node, then fresh%, held, stale, mean, p95, max, acc.
    std::regex chest_row("\n  chest +6 +([0-9.]+)% +[0-9]+ +[0-9]+ +([0-9.]+) +[0-9.]+ +([0-9.]+)");
    ASSERT_TRUE(std::regex_search(replay.output, m, chest_row)) << replay.output;
    EXPECT_GT(std::stod(m[1]), 90.0);
    EXPECT_LT(std::stod(m[2]), 1.0); // the six-sensor bound of the first test
    EXPECT_GT(std::stod(m[3]), 0.0);
    std::regex chest_quality("\n    chest +ok ");
    EXPECT_TRUE(std::regex_search(replay.output, m, chest_quality)) << replay.output;
    auto cal = read_file_bytes(dir + "/c.calibration");
    std::string cal_text(cal.begin(), cal.end());
    EXPECT_NE(cal_text.find("\nsensors pelvis left_wrist right_wrist left_shin right_shin head chest\n"),
              std::string::npos) << cal_text;
    auto csv = read_file_bytes(dir + "/f.csv");
    std::string csv_text(csv.begin(), csv.end());
    std::string header = csv_text.substr(0, csv_text.find('\n'));
    EXPECT_EQ(std::count(header.begin(), header.end(), ','), 2 + 7 * 8) << header;

    // The default six replay the same capture: the chest's node is simply not one of theirs.
    CommandResult six = run_command("replay " + dir + "/c.cap --truth " + dir + "/t.csv");
    ASSERT_EQ(six.exit_code, 0) << six.output;
    EXPECT_EQ(six.output.find("\n  chest "), std::string::npos) << six.output;

    // With the chest optional and its node silent (another node id), calibration leaves it out.
    std::string silent = "pelvis=0,left_wrist=1,right_wrist=2,left_shin=3,right_shin=4,head=5,chest=9?";
    CommandResult optional = run_command("replay " + dir + "/c.cap --sensors " + silent);
    ASSERT_EQ(optional.exit_code, 0) << optional.output;
    EXPECT_NE(optional.output.find("chest        left out"), std::string::npos) << optional.output;
    EXPECT_NE(optional.output.find("T-pose step: accepted"), std::string::npos) << optional.output;
    // Required, it is refused naming it.
    CommandResult required = run_command("replay " + dir + "/c.cap --sensors " + silent.substr(0, silent.size() - 1));
    EXPECT_EQ(required.exit_code, 1) << required.output;
    EXPECT_NE(required.output.find("REFUSED"), std::string::npos) << required.output;
    EXPECT_NE(required.output.find("reason: "), std::string::npos) << required.output;
    EXPECT_NE(required.output.substr(required.output.find("reason: ")).find("chest"), std::string::npos)
        << required.output;
}

TEST(Mocapctl, ReplayOfAMissingFileFailsWithItsName)
{
    CommandResult r = run_command("replay /nonexistent/x.cap");
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("/nonexistent/x.cap"), std::string::npos) << r.output;
}

namespace {

// `mocapctl record` from a pseudo-terminal fed with 100 synthetic 0x62 packets; shell_prefix
// runs before it in the same shell (limits). sent receives the bytes written to the port.
CommandResult record_from_pty(const std::string &shell_prefix, const std::string &out,
                              std::vector<uint8_t> &sent)
{
    int master = -1, slave = -1;
    char name[256];
    struct termios raw;
    cfmakeraw(&raw);
    if (openpty(&master, &slave, name, &raw, nullptr) != 0) return CommandResult{-1, "openpty failed"};
    close(slave);
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.motion_s = 1.0;
    auto packets = generate(cfg, "walk");
    std::thread writer([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(300));  // let mocapctl open the port
        for (size_t i = 0; i < 100 && i < packets.size(); ++i) {
            const auto &b = packets[i].bytes;
            if (write(master, b.data(), b.size()) != (ssize_t)b.size()) break;
            sent.insert(sent.end(), b.begin(), b.end());
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
    });
    CommandResult r = run_shell(shell_prefix + std::string(MOCAP_MOCAPCTL) + " record --port " + name +
                                " --out " + out + " --seconds 2");
    writer.join();
    close(master);
    return r;
}

}  // namespace

TEST(Mocapctl, RecordFromAPseudoTerminalKeepsEveryByte)
{
    std::string out = test_temp_path("recorded.cap");
    std::vector<uint8_t> sent;
    CommandResult r = record_from_pty("", out, sent);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("recorded " + std::to_string(sent.size()) + " bytes"), std::string::npos)
        << r.output;
    // The size it reports is the file's final size (read after the last flush and close).
    const size_t on_disk = read_file_bytes(out).size();
    EXPECT_NE(r.output.find("(" + std::to_string(on_disk) + " bytes on disk)"), std::string::npos)
        << r.output;

    capture_reader *reader = nullptr;
    ASSERT_EQ(capture_reader_open(out.c_str(), &reader), MOCAP_OK) << mocap_last_error();
    std::vector<uint8_t> recorded;
    int64_t ns;
    const uint8_t *data;
    size_t len;
    while (capture_reader_next(reader, &ns, &data, &len) == MOCAP_OK) recorded.insert(recorded.end(), data, data + len);
    capture_reader_close(reader);
    EXPECT_TRUE(recorded == sent);
}

// A disk that fills while recording (here a file size limit: writes past it fail with EFBIG,
// as they fail with ENOSPC on a full disk) is a failed command that says why, never exit 0.
TEST(Mocapctl, RecordOntoAFullDiskFailsAndSaysWhy)
{
    std::string out = test_temp_path("full.cap");
    std::vector<uint8_t> sent;
    // 16 blocks (8 KiB in 512-byte blocks, 16 KiB in 1 KiB ones) hold the header but not the
    // 100 packets (about 50 KB); an ignored SIGXFSZ turns the overrun into a write error.
    CommandResult r = record_from_pty("ulimit -f 16; trap '' XFSZ; ", out, sent);
    ASSERT_GT(sent.size(), 20000u);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("the recording failed"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(out), std::string::npos) << r.output;  // names the file
    EXPECT_LE(read_file_bytes(out).size(), 16384u);
}

// A path longer than the engine's path field would be cut short and open (or, for a recording,
// overwrite) some other file: refused up front, naming it.
TEST(Mocapctl, PathsLongerThanTheEngineTakesAreRefused)
{
    const std::string long_path = test_temp_dir() + "/" + std::string(300, 'x') + ".cap";
    CommandResult r = run_command("record --port /dev/ttyNOPE0 --out " + long_path + " --seconds 1");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("the recording path is"), std::string::npos) << r.output;
    CommandResult replay = run_command("replay " + long_path);
    EXPECT_NE(replay.exit_code, 0);
    EXPECT_NE(replay.output.find("the capture path is"), std::string::npos) << replay.output;
}

// A receiver that sends nothing (wrong port or baud rate, sensors off) ends `live` with a reason
// instead of a calibration countdown that waits forever.
TEST(Mocapctl, LiveOnASilentPortGivesUpWithAReason)
{
    int master = -1, slave = -1;
    char name[256];
    struct termios raw;
    cfmakeraw(&raw);
    ASSERT_EQ(openpty(&master, &slave, name, &raw, nullptr), 0);
    close(slave);
    CommandResult r = run_command(std::string("live --port ") + name + " --seconds 1");
    close(master);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("no frame from the receiver"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("--baud"), std::string::npos) << r.output;
}

// stdio reports a full disk only at flush and close: a CSV that did not reach the disk is a
// failed command, not "wrote".
TEST(Mocapctl, ACsvOnAFullDiskFailsTheReplay)
{
    std::string dir = test_temp_dir();
    CommandResult synth = run_command("synth --out " + dir + "/c.cap --motion walk --seed 5");
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    CommandResult r = run_command("replay " + dir + "/c.cap --csv /dev/full");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("writing /dev/full failed"), std::string::npos) << r.output;
}

// An output named like the capture being read would be emptied before it is read (a typo, a
// wrong tab completion): refused before anything is opened, and the capture is untouched.
TEST(Mocapctl, AnOutputThatIsTheCaptureBeingReadIsRefused)
{
    std::string dir = test_temp_dir();
    const std::string cap = dir + "/c.cap";
    ASSERT_EQ(run_command("synth --out " + cap + " --truth " + dir + "/t.csv --seconds 1").exit_code, 0);
    const std::vector<uint8_t> before = read_file_bytes(cap);
    ASSERT_GT(before.size(), 1000u);
    for (const char *opt : {"--csv", "--json", "--out", "--pose-csv", "--save-calibration"}) {
        SCOPED_TRACE(opt);
        // Another spelling of the same file counts too.
        CommandResult r = run_command("replay " + cap + " " + opt + " " + dir + "/./c.cap");
        EXPECT_EQ(r.exit_code, 2) << r.output;
        EXPECT_NE(r.output.find("is the capture this command reads"), std::string::npos) << r.output;
        EXPECT_EQ(read_file_bytes(cap), before);
    }
    CommandResult r = run_command("replay " + cap + " --truth " + dir + "/t.csv --csv " + dir + "/t.csv");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    r = run_command("synth --out " + dir + "/s.cap --truth " + dir + "/s.cap");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("name the same file"), std::string::npos) << r.output;
}

namespace {

// A command line refused as a usage error: exit status 2 and a message holding `expect`.
struct UsageErrorCase {
    std::string args, expect;
};

template <size_t N>
void expect_usage_errors(const UsageErrorCase (&cases)[N])
{
    for (const auto &c : cases) {
        CommandResult r = run_command(c.args);
        EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
        EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << "\n" << r.output;
    }
}

}  // namespace

// A missing value or a number that is not one is a usage error (exit 2) that names the option;
// before, `--seconds abc` was 0 seconds and `--out --seconds 1` wrote a file called --seconds.
TEST(Mocapctl, OptionsWithoutValuesOrWithBadNumbersAreUsageErrors)
{
    std::string dir = test_temp_dir();
    const UsageErrorCase cases[] = {
        {"synth --out " + dir + "/a.cap --seconds abc", "--seconds wants a number, got 'abc'"},
        {"synth --out " + dir + "/a.cap --seconds", "--seconds needs a value"},
        {"synth --out --seconds 1", "--out needs a value, not the option --seconds"},
        {"synth --out " + dir + "/a.cap --seconds -3", "--seconds -3 is outside"},
        {"synth --out " + dir + "/a.cap --seed 1x", "--seed wants a whole number"},
        {"synth --out " + dir + "/a.cap --corrupt 2", "--corrupt 2 is outside 0..1"},
        {"record --port /dev/null --out " + dir + "/r.cap --seconds nan", "--seconds wants a number"},
        {"replay " + dir + "/a.cap --rate 0", "--rate 0 is outside 1..1000"},
        {"bench latency --threads 100000", "--threads 100000 is outside 1..256"},
    };
    expect_usage_errors(cases);
    EXPECT_FALSE(std::filesystem::exists(dir + "/a.cap")) << "a refused command wrote its output";
    EXPECT_FALSE(std::filesystem::exists(dir + "/r.cap")) << "a refused record left a capture";
    EXPECT_FALSE(std::filesystem::exists("--seconds"));
    // Asked for, the usage is an answer: stdout, status 0; after a mistake, stderr and 2.
    CommandResult help = run_shell("(" + std::string(MOCAP_MOCAPCTL) + " replay --help 2>/dev/null)");
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_NE(help.output.find("usage: mocapctl replay CAPTURE"), std::string::npos) << help.output;
    CommandResult wrong = run_shell("(" + std::string(MOCAP_MOCAPCTL) + " frobnicate 2>/dev/null)");
    EXPECT_EQ(wrong.exit_code, 2);
    EXPECT_EQ(wrong.output.find("usage"), std::string::npos) << wrong.output;
}

// A --sensors list that is not one is a usage error naming the entry at fault, before anything
// is written.
TEST(Mocapctl, SensorsListErrorsAreUsageErrors)
{
    std::string dir = test_temp_dir();
    const std::string out = " --out " + dir + "/a.cap";
    const UsageErrorCase cases[] = {
        {"synth" + out + " --sensors pelvis=0,spine=1", "unknown segment 'spine'"},
        {"synth" + out + " --sensors pelvis=0,head=0", "node 0 is given to both pelvis and head"},
        {"synth" + out + " --sensors pelvis=0,pelvis=1", "segment pelvis is listed twice"},
        {"synth" + out + " --sensors pelvis", "'pelvis' is not SEGMENT=NODE"},
        {"synth" + out + " --sensors pelvis=x", "node 'x' of pelvis"},
        {"synth" + out + " --sensors pelvis=300", "node '300' of pelvis"},
        {"synth" + out + " --sensors pelvis=0,,head=5", "is not SEGMENT=NODE"},
        {"synth" + out + " --sensors", "--sensors needs a value"},
        {"replay " + dir + "/a.cap --sensors chest=6,chest=7?", "segment chest is listed twice"},
        {"record --port /dev/null" + out + " --sensors head=5,wrist=2", "unknown segment 'wrist'"},
        {"live --port /dev/null --sensors pelvis=0,head=0", "node 0 is given to both"},
        {"stream --vmc 127.0.0.1:1 --replay " + dir + "/a.cap --sensors knee=3", "unknown segment 'knee'"},
        {"bench pipeline --sensors knee=3", "unknown segment 'knee'"},
    };
    expect_usage_errors(cases);
    EXPECT_FALSE(std::filesystem::exists(dir + "/a.cap")) << "a refused command wrote its output";
    // The unknown-segment error lists the known ones.
    CommandResult r = run_command("synth" + out + " --sensors spine=1");
    EXPECT_NE(r.output.find("known: pelvis, left_wrist, right_wrist, left_shin, right_shin, head, chest"),
              std::string::npos) << r.output;
}

// --silence: a window of motion time in which one sensor sends nothing. Synth says so, and the
// replayed frames hold that sensor (then mark it stale) exactly in the window, the others fresh.
TEST(Mocapctl, SynthSilenceIsAGapOfThatSensorInTheReplayedFrames)
{
    std::string dir = test_temp_dir();
    CommandResult synth = run_command("synth --out " + dir + "/c.cap --motion walk --seconds 8 --seed 2 "
                                      "--silence right_wrist@3+2");
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    EXPECT_NE(synth.output.find("right_wrist silent from 3.000 s to 5.000 s of the motion"), std::string::npos)
        << synth.output;
    CommandResult replay = run_command("replay " + dir + "/c.cap --csv " + dir + "/f.csv");
    ASSERT_EQ(replay.exit_code, 0) << replay.output;

    // The session clock starts at 1 s; the prelude is 8 s: motion time 3 s is session time 12 s.
    const double gap_start = 1.0 + 8.0 + 3.0, gap_end = gap_start + 2.0, stale_after = 0.25;
    const double frame = 1.0 / 60.0, last_sample = gap_start - 1.0 / 100.0;
    auto bytes = read_file_bytes(dir + "/f.csv");
    std::istringstream csv(std::string(bytes.begin(), bytes.end()));
    std::string line;
    ASSERT_TRUE(std::getline(csv, line));
    std::vector<std::string> header;
    {
        std::istringstream h(line);
        for (std::string cell; std::getline(h, cell, ',');) header.push_back(cell);
    }
    auto column = [&](const std::string &name) {
        auto it = std::find(header.begin(), header.end(), name);
        EXPECT_NE(it, header.end()) << name;
        return (size_t)(it - header.begin());
    };
    const size_t time_col = column("time_s");
    const char *const segments[] = {"pelvis", "left_wrist", "right_wrist", "left_shin", "right_shin", "head"};
    std::vector<size_t> flag_cols;
    for (const char *seg : segments) flag_cols.push_back(column(std::string(seg) + "_flags"));
    int held = 0, stale = 0, around = 0;
    while (std::getline(csv, line)) {
        std::vector<std::string> cells;
        std::istringstream row(line);
        for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
        ASSERT_EQ(cells.size(), header.size()) << line;
        const double t = std::stod(cells[time_col]);
        if (t < gap_start - 1.0 || t > gap_end + 1.0) continue;
        for (size_t k = 0; k < flag_cols.size(); ++k) {
            const unsigned flags = (unsigned)std::stoul(cells[flag_cols[k]]);
            EXPECT_TRUE(flags & MOCAP_SENSOR_CALIBRATED) << segments[k] << " t " << t;
            const bool in_gap = k == 2 && t > gap_start - frame / 2 && t < gap_end - frame / 2;
            const bool old = in_gap && t - last_sample > stale_after;
            EXPECT_EQ((flags & MOCAP_SENSOR_HELD) != 0, in_gap) << segments[k] << " t " << t;
            EXPECT_EQ((flags & MOCAP_SENSOR_STALE) != 0, old) << segments[k] << " t " << t;
            held += (flags & MOCAP_SENSOR_HELD) != 0;
            stale += (flags & MOCAP_SENSOR_STALE) != 0;
            around += k == 2 && !in_gap;
        }
    }
    EXPECT_EQ(held, 120);   // 2 s at 60 frames/s
    EXPECT_NEAR(stale, 105, 1);
    EXPECT_GT(around, 110);  // the frames around the gap were there and fresh
    // The per-sensor summary counts the same: the right wrist's stale frames, nobody else's.
    std::smatch m;
    std::regex row("\n  right_wrist +2 +[0-9.]+% +([0-9]+) +([0-9]+)\\b");
    ASSERT_TRUE(std::regex_search(replay.output, m, row)) << replay.output;
    EXPECT_NEAR(std::stoi(m[2]), 105, 1);
    std::regex others_stale("\n  (pelvis|left_wrist|left_shin|right_shin|head) +[0-9]+ +[0-9.]+% +[0-9]+ +([1-9][0-9]*)\\b");
    EXPECT_FALSE(std::regex_search(replay.output, m, others_stale)) << replay.output;
}

TEST(Mocapctl, SilenceWindowsThatAreNotOneAreUsageErrors)
{
    std::string dir = test_temp_dir();
    const std::string out = "synth --out " + dir + "/a.cap";
    const UsageErrorCase cases[] = {
        {out + " --silence head", "--silence wants SEGMENT@START+LENGTH"},
        {out + " --silence head@2", "--silence wants SEGMENT@START+LENGTH"},
        {out + " --silence head@2+1s", "--silence wants SEGMENT@START+LENGTH"},
        {out + " --silence @2+1", "--silence wants SEGMENT@START+LENGTH"},
        {out + " --silence knee@2+1", "no segment 'knee' (pelvis, left_wrist"},
        {out + " --silence head@-2+1", "the start must be >= 0 s"},
        {out + " --silence head@2+0", "the length > 0 s"},
        {out + " --silence head@nan+1", "the start must be >= 0 s"},
        {out + " --silence chest@2+1", "chest has no sensor in the set (--sensors)"},
        {out + " --silence head@1+1 --silence", "--silence needs a value"},
    };
    expect_usage_errors(cases);
    EXPECT_FALSE(std::filesystem::exists(dir + "/a.cap")) << "a refused command wrote its output";
    // Two windows, one of them on a chest the set carries, are taken.
    CommandResult two = run_command(out + " --motion walk --seconds 4 --silence head@1+1 --sensors "
                                    "pelvis=0,left_wrist=1,right_wrist=2,left_shin=3,right_shin=4,head=5,chest=6 "
                                    "--silence chest@0+0.5");
    ASSERT_EQ(two.exit_code, 0) << two.output;
    EXPECT_NE(two.output.find("head silent from 1.000 s to 2.000 s"), std::string::npos) << two.output;
    EXPECT_NE(two.output.find("chest silent from 0.000 s to 0.500 s"), std::string::npos) << two.output;
}

// A mistyped option was ignored: the command ran with the default it was meant to change
// (`replay x.cap --sepeed 2`, `synth --seconds=5` made 30 s). Now it is refused before anything
// runs or is written, naming the command and the option.
TEST(Mocapctl, UnknownOptionsAreRefusedBeforeTheCommandRuns)
{
    std::string dir = test_temp_dir();
    const UsageErrorCase cases[] = {
        {"synth --out " + dir + "/a.cap --secnds 1", "synth has no option --secnds"},
        {"synth --out " + dir + "/a.cap --seconds=5", "write '--seconds 5'"},
        {"replay " + dir + "/a.cap --speed 2", "replay has no option --speed"},
        {"record --port /dev/null --out " + dir + "/r.cap --model m.onnx", "record has no option --model"},
        {"stream --vmc 127.0.0.1:1 --replay " + dir + "/a.cap --csv x", "stream has no option --csv"},
        {"bench decode --threads 2", "bench decode has no option --threads"},
        {"infer --model m.onnx --input i --output " + dir + "/o --frame 3", "infer has no option --frame"},
        {"version --verbose", "version has no option --verbose"},
        // Options of another mode of the command would be ignored just the same.
        {"stream --vmc 127.0.0.1:1 --port /dev/null --speed 2", "--speed applies to --replay only"},
        {"stream --vmc 127.0.0.1:1 --replay " + dir + "/a.cap --baud 9600", "--baud applies to --port only"},
        {"replay " + dir + "/a.cap --smoothing 2", "--smoothing applies to the pose model only"},
        {"replay " + dir + "/a.cap --model m.onnx --rate 30", "--rate does not apply with the pose model"},
        {"replay " + dir + "/a.cap --out " + dir + "/o.bvh --csv " + dir + "/f.csv", "use --pose-csv"},
        {"live --port /dev/null --smoothing 2", "--smoothing applies to poses only"},
    };
    expect_usage_errors(cases);
    EXPECT_FALSE(std::filesystem::exists(dir + "/a.cap")) << "a refused command wrote its output";
    EXPECT_FALSE(std::filesystem::exists(dir + "/r.cap"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/o"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/o.bvh"));
    // A value that looks like an option name is the value, not an option: a file called
    // --weird is still a file.
    ASSERT_EQ(run_command("synth --seconds 1 --out " + dir + "/a.cap --truth " + dir + "/t.csv").exit_code, 0);
    CommandResult negative = run_command("synth --out " + dir + "/b.cap --seconds -1");
    EXPECT_NE(negative.output.find("--seconds -1 is outside"), std::string::npos) << negative.output;
    // `--help` after a command is an answer too (that command's usage), but not as the value of
    // an option.
    CommandResult help = run_shell("(" + std::string(MOCAP_MOCAPCTL) + " replay --help 2>/dev/null)");
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_NE(help.output.find("usage: mocapctl replay CAPTURE"), std::string::npos) << help.output;
    EXPECT_EQ(help.output.find("mocapctl stream"), std::string::npos) << help.output;
    CommandResult named = run_shell("cd '" + dir + "' && " + std::string(MOCAP_MOCAPCTL) +
                                    " synth --out -h --seconds 1");
    EXPECT_EQ(named.exit_code, 0) << named.output;
    EXPECT_TRUE(std::filesystem::exists(dir + "/-h")) << named.output;
}

namespace {

// The options each command accepts, as main.c's table gives them (options.h).
const struct {
    const char *command, *options;
} accepted_options[] = {
    {"synth", MOCAPCTL_SYNTH_OPTIONS},
    {"replay", MOCAPCTL_REPLAY_OPTIONS},
    {"live", MOCAPCTL_LIVE_OPTIONS},
    {"record", MOCAPCTL_RECORD_OPTIONS},
    {"stream", MOCAPCTL_STREAM_OPTIONS},
    {"bench decode", MOCAPCTL_BENCH_DECODE_OPTIONS},
    {"bench", MOCAPCTL_BENCH_OPTIONS},
    {"infer", MOCAPCTL_INFER_OPTIONS},
    {"model-info", MOCAPCTL_MODEL_INFO_OPTIONS},
    {"version", MOCAPCTL_VERSION_OPTIONS},
};

std::set<std::string> accepted_by(const std::string &command)
{
    std::set<std::string> names;
    for (const auto &entry : accepted_options) {
        if (command != entry.command) continue;
        std::istringstream words(entry.options);
        for (std::string name; words >> name;) {
            if (name.back() == '=') name.pop_back();
            names.insert(name);
        }
    }
    return names;
}

// The commands `mocapctl help` lists: "  NAME   summary" lines after "commands:" (NAME may be
// two words, "bench decode"), in order, with their summaries.
std::vector<std::pair<std::string, std::string>> listed_commands(const std::string &overview)
{
    std::vector<std::pair<std::string, std::string>> listed;
    const std::regex line_form("^  ([a-z][a-z-]*(?: [a-z]+)?)  +(\\S.*)$");
    std::istringstream lines(overview);
    bool in_list = false;
    for (std::string line; std::getline(lines, line);) {
        if (line == "commands:") in_list = true;
        std::smatch m;
        if (in_list && std::regex_match(line, m, line_form)) listed.emplace_back(m[1], m[2]);
    }
    return listed;
}

// The options a text shows (every "--name"; --help is every command's).
std::set<std::string> options_shown(const std::string &text)
{
    std::set<std::string> shown;
    const std::regex option("--[a-z][a-z-]*");
    for (std::sregex_iterator it(text.begin(), text.end(), option), end; it != end; ++it)
        if (it->str() != "--help") shown.insert(it->str());
    return shown;
}

// `mocapctl COMMAND --help` (stdout only) of every command the overview lists, by name.
std::map<std::string, CommandResult> every_command_help(std::string *overview)
{
    CommandResult help = run_shell("(" + std::string(MOCAP_MOCAPCTL) + " help 2>/dev/null)");
    EXPECT_EQ(help.exit_code, 0);
    *overview = help.output;
    std::map<std::string, CommandResult> helps;
    for (const auto &listed : listed_commands(help.output))
        helps[listed.first] = run_shell("(" + std::string(MOCAP_MOCAPCTL) + " " + listed.first +
                                        " --help 2>/dev/null)");
    return helps;
}

}  // namespace

// `mocapctl help` and `mocapctl --help` are the overview: every command of the table on a line
// of its own with a one-line summary, and none of the commands' options (those are each
// command's own --help).
TEST(Mocapctl, HelpListsEveryCommandWithASummary)
{
    CommandResult help = run_shell("(" + std::string(MOCAP_MOCAPCTL) + " help 2>/dev/null)");
    CommandResult dashed = run_shell("(" + std::string(MOCAP_MOCAPCTL) + " --help 2>/dev/null)");
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_EQ(dashed.exit_code, 0);
    EXPECT_EQ(help.output, dashed.output);
    std::vector<std::string> names;
    for (const auto &[name, summary] : listed_commands(help.output)) {
        names.push_back(name);
        EXPECT_GT(summary.size(), 10u) << name << ": " << summary;
    }
    std::vector<std::string> table;
    for (const auto &entry : accepted_options) table.push_back(entry.command);
    EXPECT_EQ(names, table) << help.output;
    EXPECT_EQ(options_shown(help.output), std::set<std::string>{}) << help.output;
    // Without a command, the overview is the usage error's message.
    CommandResult bare = run_shell("(" + std::string(MOCAP_MOCAPCTL) + " 2>&1 >/dev/null)");
    EXPECT_EQ(bare.exit_code, 2);
    EXPECT_EQ(bare.output, help.output);
}

// `mocapctl COMMAND --help` is that command's usage: on stdout with status 0, naming the command,
// showing options it takes and none it does not take (another command's).
TEST(Mocapctl, ACommandsHelpShowsItsOwnOptionsAndNoOther)
{
    std::string overview;
    std::map<std::string, CommandResult> helps = every_command_help(&overview);
    ASSERT_EQ(helps.size(), std::size(accepted_options)) << overview;
    for (const auto &[command, help] : helps) {
        EXPECT_EQ(help.exit_code, 0) << command;
        EXPECT_EQ(help.output.rfind("usage: mocapctl " + command, 0), 0u) << command << "\n" << help.output;
        const std::set<std::string> accepted = accepted_by(command);
        for (const std::string &option : options_shown(help.output))
            EXPECT_EQ(accepted.count(option), 1u)
                << "mocapctl " << command << " --help shows " << option << ", which "
                << command << " does not take:\n" << help.output;
        for (const auto &other : accepted_options) {
            const std::string name = other.command;
            if (name == command || command.rfind(name + " ", 0) == 0) continue;
            EXPECT_EQ(help.output.find("mocapctl " + name + " "), std::string::npos)
                << command << "'s help shows " << name << "'s usage:\n" << help.output;
        }
    }
    // Options that are one command's only, in its help and not in the others'.
    const std::pair<const char *, const char *> own[] = {
        {"synth", "--trajectory"}, {"replay", "--metrics-json"}, {"live", "--pose"},
        {"stream", "--vmc"},       {"bench", "--max-characters"}, {"infer", "--provider"},
    };
    for (const auto &[command, option] : own) {
        for (const auto &[name, help] : helps) {
            const bool shown = options_shown(help.output).count(option) == 1;
            EXPECT_EQ(shown, name == command) << option << " in mocapctl " << name << " --help:\n"
                                              << help.output;
        }
    }
    // `mocapctl help COMMAND` says the same; `bench decode` is a command of its own.
    CommandResult topic = run_shell("(" + std::string(MOCAP_MOCAPCTL) + " help stream 2>/dev/null)");
    EXPECT_EQ(topic.exit_code, 0);
    EXPECT_EQ(topic.output, helps["stream"].output);
    EXPECT_EQ(options_shown(helps["bench decode"].output), std::set<std::string>{"--seconds"});
}

// An unknown command is named, with where the commands are listed, on stderr with status 2;
// nothing else is printed (no usage to scroll past).
TEST(Mocapctl, AnUnknownCommandIsNamed)
{
    const std::string expected = "mocapctl: unknown command 'frob' (mocapctl help lists them)\n";
    for (const std::string &args : {std::string("frob"), std::string("frob --out x.cap"),
                                    std::string("help frob")}) {
        CommandResult stderr_only =
            run_shell("(" + std::string(MOCAP_MOCAPCTL) + " " + args + " 2>&1 >/dev/null)");
        EXPECT_EQ(stderr_only.exit_code, 2) << args;
        EXPECT_EQ(stderr_only.output, expected) << args;
        CommandResult stdout_only =
            run_shell("(" + std::string(MOCAP_MOCAPCTL) + " " + args + " 2>/dev/null)");
        EXPECT_EQ(stdout_only.output, "") << args;
    }
    EXPECT_FALSE(std::filesystem::exists("x.cap"));
}

// Every option a command's help shows is one it takes when run: the list that refuses unknown
// options and the help users read cannot drift apart.
TEST(Mocapctl, EveryOptionInTheUsageTextIsAccepted)
{
    std::string overview;
    size_t tried = 0;
    for (const auto &[command, help] : every_command_help(&overview)) {
        // "bench" alone is the usage error of a missing bench name; latency takes the model options.
        const std::string words = command == "bench" ? "bench latency" : command;
        for (const std::string &option : options_shown(help.output)) {
            // Only the option check runs: every command needs more than this one option, so each
            // stops at its own usage error (or a missing value) without doing anything.
            CommandResult r = run_shell("timeout 20 " + std::string(MOCAP_MOCAPCTL) + " " + words +
                                        " " + option + " </dev/null");
            EXPECT_EQ(r.output.find("has no option"), std::string::npos) << words << " " << option
                                                                          << "\n" << r.output;
            ++tried;
        }
    }
    EXPECT_GT(tried, 50u) << overview;
}

// ... and every option a command accepts is one its help shows: none is hidden from users.
TEST(Mocapctl, EveryAcceptedOptionIsInTheUsageText)
{
    std::string overview;
    std::map<std::string, CommandResult> helps = every_command_help(&overview);
    size_t checked = 0;
    for (const auto &entry : accepted_options) {
        const std::set<std::string> shown = options_shown(helps[entry.command].output);
        for (const std::string &name : accepted_by(entry.command)) {
            EXPECT_EQ(shown.count(name), 1u) << "mocapctl " << entry.command << " accepts " << name
                                             << " but its help does not show it:\n"
                                             << helps[entry.command].output;
            ++checked;
        }
    }
    EXPECT_GT(checked, 50u) << overview;
}

// A command blocked in I/O (here: opening a named pipe nobody reads) cannot act on the first
// Ctrl-C; the second ends it.
TEST(Mocapctl, ASecondCtrlCEndsACommandBlockedInIo)
{
    std::string dir = test_temp_dir();
    // The outer timeout only guards the test; the answer is the command's own exit status.
    CommandResult r = run_shell("cd '" + dir + "' && mkfifo pipe && timeout -s KILL 20 sh -c '" +
                                std::string(MOCAP_MOCAPCTL) +
                                " synth --out pipe --seconds 1 & pid=$!; sleep 1; kill -INT $pid; "
                                "sleep 0.5; kill -0 $pid && echo still-running-after-one; kill -INT $pid; "
                                "wait $pid; echo rc=$?'");
    EXPECT_NE(r.output.find("still-running-after-one"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("rc=130"), std::string::npos) << r.output;   // ended by SIGINT, not by KILL
}

// The replay resynchronises past damaged chunks and ignores a cut-off end, as it must; the
// command says what was left out, so results from part of a capture are not taken for the whole.
TEST(Mocapctl, AReplayOfADamagedCaptureSaysWhatWasLeftOut)
{
    std::string dir = test_temp_dir();
    const std::string cap = dir + "/c.cap";
    ASSERT_EQ(run_command("synth --out " + cap + " --seconds 3").exit_code, 0);
    CommandResult clean = run_command("replay " + cap);
    EXPECT_EQ(clean.exit_code, 0) << clean.output;
    EXPECT_EQ(clean.output.find("warning"), std::string::npos) << clean.output;
    std::vector<uint8_t> bytes = read_file_bytes(cap);
    ASSERT_GT(bytes.size(), 200000u);
    for (size_t k = 0; k < 3; ++k) bytes[bytes.size() / 3 + k * 30000] ^= 0xff;   // three chunks
    bytes.resize(bytes.size() - 100);                                           // and a cut end
    write_file_bytes(dir + "/damaged.cap", bytes);
    CommandResult r = run_command("replay " + dir + "/damaged.cap");
    EXPECT_EQ(r.exit_code, 0) << r.output;   // what could be read is still replayed
    EXPECT_NE(r.output.find("3 damaged chunk(s) were skipped"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("ends in a damaged or incomplete chunk"), std::string::npos) << r.output;
}

TEST(Mocapctl, LiveOnAWrongPortNamesIt)
{
    CommandResult r = run_command("live --port /dev/ttyNOPE0 --seconds 1");
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("/dev/ttyNOPE0"), std::string::npos) << r.output;
}

// `synth --seconds` longer than the motion gave a shorter capture without a word; the summary
// now says how long the motion part is, and a note says when --seconds was cut.
TEST(Mocapctl, SynthSaysHowLongTheMotionIsAndWhenSecondsWasCut)
{
    std::string dir = test_temp_dir();
    CommandResult walk = run_command("synth --out " + dir + "/w.cap --motion walk --seconds 4");
    ASSERT_EQ(walk.exit_code, 0) << walk.output;
    EXPECT_NE(walk.output.find("then 4.0 s of walk"), std::string::npos) << walk.output;
    EXPECT_EQ(walk.output.find("note:"), std::string::npos) << walk.output;

    CommandResult whole = run_command("synth --out " + dir + "/m.cap");
    ASSERT_EQ(whole.exit_code, 0) << whole.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(whole.output, m, std::regex("then ([0-9.]+) s of mixed")))
        << whole.output;
    const double length = std::stod(m[1]);
    EXPECT_GT(length, 10.0);
    EXPECT_EQ(whole.output.find("note:"), std::string::npos) << whole.output;

    CommandResult longer = run_command("synth --out " + dir + "/l.cap --seconds 1000");
    ASSERT_EQ(longer.exit_code, 0) << longer.output;
    EXPECT_NE(longer.output.find("the motion ends after " + std::string(m[1]) +
                                 " s, so the capture is shorter than --seconds 1000"),
              std::string::npos) << longer.output;
    // The capture itself is the whole motion either way (the header's creation time differs).
    EXPECT_EQ(read_file_bytes(dir + "/l.cap").size(), read_file_bytes(dir + "/m.cap").size());
}

#include <algorithm>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

namespace {

// Arrival times (seconds, steady clock) of the UDP datagrams a `mocapctl stream` run sends to a
// loopback port of our own, and the command's result.
struct StreamArrivals {
    std::vector<double> times;
    CommandResult result;
};

StreamArrivals receive_stream(const std::string &args_before_port, const std::string &args_after_port)
{
    StreamArrivals out;
    int fd = socket(AF_INET, SOCK_DGRAM, 0);
    int big = 4 << 20;  // room for a --fast burst while this thread waits for a core
    if (fd >= 0) setsockopt(fd, SOL_SOCKET, SO_RCVBUF, (const char *)&big, sizeof big);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = 0;
    socklen_t len = sizeof a;
    if (fd < 0 || bind(fd, (sockaddr *)&a, sizeof a) != 0 || getsockname(fd, (sockaddr *)&a, &len) != 0) {
        ADD_FAILURE() << "no loopback UDP socket";
        return out;
    }
    const std::string port = std::to_string(ntohs(a.sin_port));
    std::atomic<bool> done{false};
    std::thread runner([&] {
        out.result = run_command(args_before_port + port + args_after_port);
        done = true;
    });
    auto t0 = std::chrono::steady_clock::now();
    char buf[65536];
    for (;;) {
        pollfd p{fd, POLLIN, 0};
        if (poll(&p, 1, 20) > 0 && recv(fd, buf, sizeof buf, 0) > 0) {
            out.times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
            continue;
        }
        if (done) break;
    }
    runner.join();
    close(fd);
    return out;
}

}  // namespace

// A replay streams at the capture's pace, one bundle per model frame, evenly: a receiver sees
// a bundle every 1/60 s, not bursts as the engine happens to solve them. --fast does not wait.
TEST(Mocapctl, StreamPacesAReplayEvenlyByDefaultAndFastDoesNot)
{
    std::string dir = test_temp_dir();
    ASSERT_EQ(run_command("synth --out " + dir + "/s.cap --motion walk --seconds 2 --seed 4").exit_code, 0);
    StreamArrivals paced = receive_stream("stream --vmc 127.0.0.1:", " --replay " + dir + "/s.cap --smoothing 0");
    ASSERT_EQ(paced.result.exit_code, 0) << paced.result.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(paced.result.output, m, std::regex("(\\d+) bundles sent"))) << paced.result.output;
    const size_t sent = std::stoul(m[1]);
    ASSERT_GT(sent, 120u) << paced.result.output;
    ASSERT_EQ(paced.times.size(), sent) << "every bundle arrived (loopback)";

    std::vector<double> gaps;
    for (size_t i = 1; i < paced.times.size(); ++i) gaps.push_back(paced.times[i] - paced.times[i - 1]);
    std::vector<double> sorted = gaps;
    std::sort(sorted.begin(), sorted.end());
    const double period = 1.0 / 60.0;
    EXPECT_NEAR(sorted[sorted.size() / 2], period, 0.0015) << "median gap";
    size_t even = std::count_if(gaps.begin(), gaps.end(), [&](double g) { return std::fabs(g - period) < 0.005; });
    EXPECT_GE((double)even, 0.8 * gaps.size()) << even << " of " << gaps.size() << " gaps within 5 ms of 1/60 s";
    const double span = paced.times.back() - paced.times.front();
    EXPECT_NEAR(span, (sent - 1) * period, 0.05 * (sent - 1) * period) << "the capture's own duration";

    StreamArrivals fast = receive_stream("stream --vmc 127.0.0.1:", " --replay " + dir + "/s.cap --smoothing 0 --fast --rate 1000");
    ASSERT_EQ(fast.result.exit_code, 0) << fast.result.output;
    ASSERT_TRUE(std::regex_search(fast.result.output, m, std::regex("(\\d+) bundles sent"))) << fast.result.output;
    ASSERT_EQ(std::stoul(m[1]), sent) << fast.result.output;
    // A burst over UDP may lose a few datagrams when the receiving thread waits for a core on a
    // busy machine (seen: 160 of 166); the paced run above must lose none.
    ASSERT_GE(fast.times.size(), sent * 9 / 10) << fast.result.output;
    EXPECT_LT(fast.times.back() - fast.times.front(), span / 2) << "--fast does not wait for the pace";

    CommandResult both = run_command("stream --vmc 127.0.0.1:9 --replay " + dir + "/s.cap --fast --speed 2");
    EXPECT_EQ(both.exit_code, 2) << both.output;
    EXPECT_NE(both.output.find("cannot be combined"), std::string::npos) << both.output;
}
