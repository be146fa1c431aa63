// `mocapctl stream --vmc` received by a real OSC implementation: liblo's oscdump (Debian
// liblo-tools). A generated capture is streamed through the shipped model; the test parses what
// oscdump printed and checks every bundle (OK, T, Root/Pos, each mapped HumanBodyBones bone once)
// and that the rotations equal the engine's own poses (`mocapctl replay --model --json` on the
// same capture) converted to Unity's frame. oscdump can only bind every interface, so it and
// mocapctl run in a private network namespace (unshare -rn) that has nothing but loopback.
#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.h"

extern "C" {
#include "onnx_runtime.h"
}

namespace fs = std::filesystem;

namespace {

const fs::path kShippedModel =
    fs::path(__FILE__).parent_path() / ".." / ".." / "Runtime" / "Models" / "mocap_pose_fp32.onnx";

using Result = CommandResult;
Result run(const std::string &cmd) { return run_shell(cmd); }

const char *kOscdump = "/usr/bin/oscdump";

struct PoseRow {
    double t;
    double q[24][4];
    double root[3];
};

std::vector<PoseRow> read_json_poses(const std::string &path)
{
    std::vector<PoseRow> rows;
    std::ifstream f(path);
    std::string line;
    while (std::getline(f, line)) {
        PoseRow r{};
        size_t at = line.find("\"time_s\":");
        size_t rp = line.find("\"root_position\":[");
        size_t jr = line.find("\"joint_rotations\":[");
        if (at == std::string::npos || jr == std::string::npos || rp == std::string::npos) continue;
        r.t = std::strtod(line.c_str() + at + 9, nullptr);
        const char *p = line.c_str() + rp + 17;
        for (int k = 0; k < 3; ++k) {
            char *end;
            r.root[k] = std::strtod(p, &end);
            p = end + 1;
        }
        p = line.c_str() + jr + 19;
        for (int j = 0; j < 24; ++j) {
            while (*p == '[' || *p == ',') ++p;
            for (int k = 0; k < 4; ++k) {
                char *end;
                r.q[j][k] = std::strtod(p, &end);
                p = end;
                if (*p == ',') ++p;
            }
            while (*p == ']') ++p;
        }
        rows.push_back(r);
    }
    return rows;
}

struct DumpMessage {
    std::string stamp, address, types;
    std::vector<std::string> strings;
    std::vector<double> numbers;
};

// oscdump prints one line per message: "<bundle timetag> <address> <types> <args...>".
std::vector<DumpMessage> read_dump(const std::string &path)
{
    std::vector<DumpMessage> out;
    std::ifstream f(path);
    std::string line;
    while (std::getline(f, line)) {
        std::istringstream in(line);
        DumpMessage m;
        if (!(in >> m.stamp >> m.address >> m.types)) continue;
        if (m.address[0] != '/') continue;
        for (char t : m.types) {
            std::string tok;
            in >> tok;
            if (t == 's') {
                if (tok.size() >= 2 && tok.front() == '"' && tok.back() == '"') tok = tok.substr(1, tok.size() - 2);
                m.strings.push_back(tok);
            } else {
                m.numbers.push_back(std::strtod(tok.c_str(), nullptr));
            }
        }
        out.push_back(m);
    }
    return out;
}

}  // namespace

TEST(VmcOscdump, StreamedReplayIsReceivedByOscdumpAndMatchesTheEnginePoses)
{
    if (access(kOscdump, X_OK) != 0) GTEST_SKIP() << "oscdump (Debian liblo-tools) is not installed";
    if (!ort_library_available(nullptr)) GTEST_SKIP() << "ONNX Runtime not available: " << mocap_last_error();
    Result ns = run("unshare -rn sh -c 'ip link set lo up && cat /proc/net/if_inet6 >/dev/null; echo ok'");
    ASSERT_EQ(ns.exit_code, 0) << "cannot create a private network namespace (unshare -rn), so "
                                  "oscdump cannot be confined to loopback: " << ns.output;

    const std::string dir = test_temp_dir() + "/pid" + std::to_string(getpid());
    fs::create_directories(dir);
    const std::string capture = dir + "/walk.cap", json = dir + "/poses.jsonl", dump = dir + "/oscdump.txt";
    const std::string model = kShippedModel.string();
    const std::string ctl = MOCAP_MOCAPCTL;
    Result r = run(ctl + " synth --out " + capture + " --seconds 3 --motion walk");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = run(ctl + " replay " + capture + " --model " + model + " --json " + json);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::vector<PoseRow> poses = read_json_poses(json);
    ASSERT_GT(poses.size(), 100u);

    // Inside the namespace: oscdump on the VMC default port, wait until it is bound (port 39539 =
    // 0x9A73 in /proc/net/udp), stream at 4x the recorded pace, give oscdump time to print, stop it.
    const std::string script =
        "ip link set lo up || exit 90\n"
        "'" + std::string(kOscdump) + "' -L 39539 > '" + dump + "' 2>&1 &\n"
        "OD=$!\n"
        "for i in $(seq 100); do grep -qi ':9A73 ' /proc/net/udp /proc/net/udp6 2>/dev/null && break; sleep 0.05; done\n"
        "'" + ctl + "' stream --vmc 127.0.0.1:39539 --replay '" + capture + "' --model '" + model + "' --speed 4\n"
        "RC=$?\n"
        "sleep 0.5\n"
        "kill $OD\n"
        "exit $RC\n";
    std::ofstream(dir + "/stream.sh") << script;
    r = run("unshare -rn sh '" + dir + "/stream.sh'");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("22 bones each"), std::string::npos) << r.output;

    std::vector<DumpMessage> msgs = read_dump(dump);
    ASSERT_FALSE(msgs.empty()) << "oscdump printed nothing";
    // Bundles: each starts with /VMC/Ext/OK; all its messages carry the same bundle timetag.
    std::vector<std::vector<DumpMessage>> bundles;
    for (const auto &m : msgs) {
        if (m.address == "/VMC/Ext/OK") bundles.emplace_back();
        ASSERT_FALSE(bundles.empty()) << "message before the first /VMC/Ext/OK: " << m.address;
        bundles.back().push_back(m);
    }
    EXPECT_EQ(bundles.size(), poses.size()) << "every pose is one bundle (rate cap 60 = model rate)";

    const std::vector<std::string> bones = {
        "Hips", "LeftUpperLeg", "RightUpperLeg", "Spine", "LeftLowerLeg", "RightLowerLeg", "Chest",
        "LeftFoot", "RightFoot", "UpperChest", "LeftToes", "RightToes", "Neck", "LeftShoulder",
        "RightShoulder", "Head", "LeftUpperArm", "RightUpperArm", "LeftLowerArm", "RightLowerArm",
        "LeftHand", "RightHand"};  // bone i is SMPL joint i
    size_t matched = 0, pi = 0;
    double worst = 0;
    for (const auto &b : bundles) {
        ASSERT_EQ(b.size(), 3u + bones.size());
        for (const auto &m : b) EXPECT_EQ(m.stamp, b[0].stamp);
        EXPECT_EQ(b[0].types, "iii");
        EXPECT_EQ(b[0].numbers, (std::vector<double>{1, 3, 0}));
        ASSERT_EQ(b[1].address, "/VMC/Ext/T");
        ASSERT_EQ(b[2].address, "/VMC/Ext/Root/Pos");
        ASSERT_EQ(b[2].strings, std::vector<std::string>{"root"});
        std::map<std::string, int> seen;
        for (size_t k = 0; k < bones.size(); ++k) {
            const DumpMessage &m = b[3 + k];
            ASSERT_EQ(m.address, "/VMC/Ext/Bone/Pos");
            ASSERT_EQ(m.types, "sfffffff");
            ASSERT_EQ(m.strings.size(), 1u);
            EXPECT_EQ(m.strings[0], bones[k]);
            seen[m.strings[0]]++;
        }
        EXPECT_EQ(seen.size(), bones.size());
        // The engine's pose at this bundle's time.
        const double t = b[1].numbers[0];
        while (pi < poses.size() && poses[pi].t < t - 1e-3) ++pi;
        ASSERT_LT(pi, poses.size()) << "no engine pose at t=" << t;
        ASSERT_NEAR(poses[pi].t, t, 1e-3);
        const PoseRow &p = poses[pi];
        for (size_t j = 0; j < bones.size(); ++j) {
            const std::vector<double> &f = b[3 + j].numbers;  // px py pz qx qy qz qw
            const double expected[4] = {p.q[j][1], -p.q[j][2], -p.q[j][3], p.q[j][0]};
            for (int k = 0; k < 4; ++k) {
                worst = std::max(worst, std::fabs(f[3 + k] - expected[k]));
                EXPECT_NEAR(f[3 + k], expected[k], 1e-4) << bones[j] << " t=" << t;
            }
        }
        // Root: X mirrored, on the floor under the pelvis (rest height 0.93 of the shipped model
        // is not assumed: Root.y + Hips.y must be the pelvis height).
        const std::vector<double> &root = b[2].numbers, &hips = b[3].numbers;
        EXPECT_NEAR(root[0] + hips[0], -p.root[0], 1e-4);
        EXPECT_NEAR(root[1] + hips[1], p.root[1], 1e-4);
        EXPECT_NEAR(root[2] + hips[2], p.root[2], 1e-4);
        matched++;
    }
    EXPECT_EQ(matched, poses.size());
    std::printf("%zu bundles from oscdump matched the engine's poses (worst rotation difference %.2e)\n",
                matched, worst);
}
