// The streaming BVH writer: Euler decomposition, continuity, crash safety, and a round trip
// through an independent reader (training/bvh.py, via tests/bvh_read_check.py).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>


#include "test_support.h"

extern "C" {
#include "bvh_writer.h"
#include "mocap_math.h"
}

namespace fs = std::filesystem;

namespace {

const fs::path kTestsDir = fs::path(__FILE__).parent_path();

const char *const kNames[24] = {
    "pelvis",     "left_hip",       "right_hip",      "spine1",      "left_knee",   "right_knee",
    "spine2",     "left_ankle",     "right_ankle",    "spine3",      "left_foot",   "right_foot",
    "neck",       "left_collar",    "right_collar",   "head",        "left_shoulder", "right_shoulder",
    "left_elbow", "right_elbow",    "left_wrist",     "right_wrist", "left_hand",   "right_hand"};
const int kParents[24] = {-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21};

bvh_skeleton smpl_skeleton()
{
    bvh_skeleton sk;
    std::memset(&sk, 0, sizeof sk);
    sk.joint_count = 24;
    for (int j = 0; j < 24; ++j) {
        std::snprintf(sk.names[j], BVH_NAME_CAP, "%s", kNames[j]);
        sk.parents[j] = kParents[j];
        // Distinct, plausible offsets (metres): the check compares them exactly.
        sk.offsets[j][0] = j == 0 ? 0.0f : 0.01f * (float)((j % 5) - 2);
        sk.offsets[j][1] = j == 0 ? 0.93f : -0.05f - 0.01f * (float)j;
        sk.offsets[j][2] = j == 0 ? 0.0f : 0.002f * (float)(j % 3);
    }
    return sk;
}

void rotation_of(const double angles[3], bvh_rotation_order order, double m[9])
{
    int ax[3] = {2, 0, 1};
    if (order == BVH_ORDER_XYZ) ax[0] = 0, ax[1] = 1, ax[2] = 2;
    mat3_identity(m);
    for (int k = 0; k < 3; ++k) {
        double r[9], t[9];
        if (ax[k] == 0) {
            mat3_rotation_x(r, angles[k]);
        } else if (ax[k] == 1) {
            mat3_rotation_y(r, angles[k]);
        } else {
            mat3_rotation_z(r, angles[k]);
        }
        mat3_multiply(t, m, r);
        std::memcpy(m, t, sizeof t);
    }
}

double angle_between(const double a[9], const double b[9]) { return mat3_angle_deg(a, b); }


[[maybe_unused]] std::string run_capture(const std::string &cmd, int *rc)
{
    std::string out;
    FILE *p = popen(cmd.c_str(), "r");
    if (!p) {
        *rc = -1;
        return out;
    }
    std::array<char, 65536> buf;
    size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), n);
    int status = pclose(p);
#if defined(_WIN32)
    *rc = status;
#else
    *rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
#endif
    return out;
}

std::string slurp(const std::string &path)
{
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

// Frames declared in the header and complete data lines after "Frame Time".
void count_frames(const std::string &text, long *declared, long *lines)
{
    *declared = -1;
    *lines = 0;
    size_t fpos = text.find("Frames:");
    if (fpos == std::string::npos) return;
    *declared = std::strtol(text.c_str() + fpos + 7, nullptr, 10);
    size_t t = text.find("Frame Time:", fpos);
    if (t == std::string::npos) return;
    size_t nl = text.find('\n', t);
    while (nl != std::string::npos && nl + 1 < text.size()) {
        size_t next = text.find('\n', nl + 1);
        if (next == std::string::npos) break;  // an unterminated line is not complete
        (*lines)++;
        nl = next;
    }
}

// A quaternion (w,x,y,z) from intrinsic angles for the test's frames.
[[maybe_unused]] void quat_of_angles(const double angles[3], bvh_rotation_order order, float q[4])
{
    double m[9], qd[4];
    rotation_of(angles, order, m);
    mat3_to_quat(qd, m);
    for (int k = 0; k < 4; ++k) q[k] = (float)qd[k];
}

}  // namespace

TEST(BvhEuler, DecomposesRandomRotationsInBothOrders)
{
    mocap_rng rng;
    mocap_rng_seed(&rng, 42);
    for (int order = 0; order < 2; ++order) {
        for (int i = 0; i < 2000; ++i) {
            double q[4], m[9], angles[3], back[9];
            mocap_rng_rotation(&rng, q);
            quat_to_mat3(m, q);
            bvh_euler_from_matrix(m, (bvh_rotation_order)order, nullptr, angles);
            rotation_of(angles, (bvh_rotation_order)order, back);
            ASSERT_LT(angle_between(m, back), 1e-6) << "order " << order << " sample " << i;
        }
    }
}

TEST(BvhEuler, OrderMattersAndMatchesTheChannelConvention)
{
    // R = Rz(30) Rx(20) Ry(10) must give exactly (30, 20, 10) in ZXY and something else in XYZ.
    const double d = M_PI / 180.0;
    double angles[3] = {30 * d, 20 * d, 10 * d}, m[9], out[3], back[9];
    rotation_of(angles, BVH_ORDER_ZXY, m);
    bvh_euler_from_matrix(m, BVH_ORDER_ZXY, nullptr, out);
    EXPECT_NEAR(out[0] / d, 30.0, 1e-9);
    EXPECT_NEAR(out[1] / d, 20.0, 1e-9);
    EXPECT_NEAR(out[2] / d, 10.0, 1e-9);
    bvh_euler_from_matrix(m, BVH_ORDER_XYZ, nullptr, out);
    EXPECT_GT(std::fabs(out[0] / d - 30.0), 1.0);
    rotation_of(out, BVH_ORDER_XYZ, back);
    EXPECT_LT(angle_between(m, back), 1e-6);
}

TEST(BvhEuler, GimbalLockStillReproducesTheRotation)
{
    const double d = M_PI / 180.0;
    for (int order = 0; order < 2; ++order) {
        for (double mid : {90.0, -90.0, 89.99999, -89.99999}) {
            double angles[3] = {40 * d, mid * d, -25 * d}, m[9], out[3], back[9];
            rotation_of(angles, (bvh_rotation_order)order, m);
            bvh_euler_from_matrix(m, (bvh_rotation_order)order, nullptr, out);
            rotation_of(out, (bvh_rotation_order)order, back);
            EXPECT_LT(angle_between(m, back), 1e-4) << "order " << order << " middle " << mid;
        }
    }
}

TEST(BvhEuler, AnglesStayContinuousThroughFullTurns)
{
    // A joint spinning about Y through three full turns while tilting: no jump between frames.
    const double d = M_PI / 180.0;
    double prev[3] = {0, 0, 0};
    bool have = false;
    for (int f = 0; f <= 1080; ++f) {
        double truth[3] = {15 * d * std::sin(f * 0.01), 10 * d, f * d}; // ZXY: spin in Y
        double m[9], out[3], back[9];
        rotation_of(truth, BVH_ORDER_ZXY, m);
        bvh_euler_from_matrix(m, BVH_ORDER_ZXY, have ? prev : nullptr, out);
        rotation_of(out, BVH_ORDER_ZXY, back);
        ASSERT_LT(angle_between(m, back), 1e-6);
        if (have) {
            for (int k = 0; k < 3; ++k) ASSERT_LT(std::fabs(out[k] - prev[k]), 2.0 * d) << "frame " << f;
        }
        std::memcpy(prev, out, sizeof prev);
        have = true;
    }
    EXPECT_NEAR(prev[2] / d, 1080.0, 1e-6); // unwrapped, not folded into (-180, 180]
}

#if !defined(_WIN32) // Windows: Linux Python cannot be started from inside Wine
TEST(BvhWriter, RoundTripThroughTheIndependentPythonReader)
{
    const std::string py = python_with_numpy();
    ASSERT_FALSE(py.empty()) << "python3 with numpy is needed (or set MOCAP_PYTHON)";
    for (int order = 0; order < 2; ++order) {
        const bvh_rotation_order ord = (bvh_rotation_order)order;
        const std::string path = test_temp_path(order == 0 ? "zxy.bvh" : "xyz.bvh");
        const bvh_skeleton sk = smpl_skeleton();
        bvh_writer *w = nullptr;
        ASSERT_EQ(bvh_writer_open(path.c_str(), &sk, 1.0 / 60.0, ord, &w), MOCAP_OK)
            << mocap_last_error();
        bvh_writer_set_flush_every(w, 7);
        const int frames = 75;
        mocap_rng rng;
        mocap_rng_seed(&rng, 7 + order);
        std::vector<std::array<float, 3>> roots(frames);
        std::vector<std::array<std::array<float, 4>, 24>> rots(frames);
        std::array<std::array<double, 4>, 24> base;
        for (auto &b : base) mocap_rng_rotation(&rng, b.data());
        for (int f = 0; f < frames; ++f) {
            roots[f] = {0.01f * f, 0.9f + 0.05f * std::sin(0.2f * f), -0.02f * f};
            for (int j = 0; j < 24; ++j) {
                // A large random rotation per joint, turning steadily (crosses +-180 degrees).
                double axis[3] = {0.3, 1.0, -0.2}, spin[4], q[4];
                quat_from_axis_angle(spin, axis, 0.09 * f * (1 + j % 3));
                quat_multiply(q, base[j].data(), spin);
                if (f % 2) {
                    for (double &v : q) v = -v; // the sign of q must not matter
                }
                for (int k = 0; k < 4; ++k) rots[f][j][k] = (float)q[k];
            }
            if (f == 10) { // gimbal lock on one joint, in this order's middle axis
                const double a[3] = {0.4, M_PI / 2, -0.3};
                quat_of_angles(a, ord, rots[f][5].data());
            }
            ASSERT_EQ(bvh_writer_append(w, roots[f].data(), (const float(*)[4])rots[f].data()), MOCAP_OK)
                << mocap_last_error();
        }
        EXPECT_EQ(bvh_writer_frames(w), (uint64_t)frames);
        ASSERT_EQ(bvh_writer_close(w), MOCAP_OK) << mocap_last_error();

        int rc = -1;
        std::string out = run_capture("\"" + py + "\" \"" + (kTestsDir / "bvh_read_check.py").string() +
                                          "\" \"" + path + "\" 2>&1",
                                      &rc);
        ASSERT_EQ(rc, 0) << out;
        std::istringstream in(out);
        std::string line;
        int read_frames = -1;
        double frame_time = 0;
        std::vector<std::string> joints;
        std::map<std::string, std::array<double, 3>> offsets;
        int checked = 0;
        double worst = 0, worst_root = 0;
        while (std::getline(in, line)) {
            std::istringstream ls(line);
            std::string kind;
            ls >> kind;
            if (kind == "frames") ls >> read_frames;
            else if (kind == "frame_time") ls >> frame_time;
            else if (kind == "joints") {
                std::string n;
                while (ls >> n) joints.push_back(n);
            } else if (kind == "offset") {
                std::string n;
                std::array<double, 3> o;
                ls >> n >> o[0] >> o[1] >> o[2];
                offsets[n] = o;
            } else if (kind == "root") {
                int f;
                double p[3];
                ls >> f >> p[0] >> p[1] >> p[2];
                for (int k = 0; k < 3; ++k) worst_root = std::max(worst_root, std::fabs(p[k] - roots[f][k]));
            } else if (kind == "rot") {
                int f;
                std::string n;
                double m[9];
                ls >> f >> n;
                for (double &v : m) ls >> v;
                int j = -1;
                for (int k = 0; k < 24; ++k)
                    if (n == kNames[k]) j = k;
                ASSERT_GE(j, 0) << n;
                double q[4] = {rots[f][j][0], rots[f][j][1], rots[f][j][2], rots[f][j][3]}, want[9];
                quat_normalize(q);
                quat_to_mat3(want, q);
                worst = std::max(worst, angle_between(m, want));
                checked++;
            }
        }
        EXPECT_EQ(read_frames, frames);
        EXPECT_NEAR(frame_time, 1.0 / 60.0, 1e-8);
        ASSERT_EQ(joints.size(), 24u);
        EXPECT_EQ(joints[0], "pelvis");
        for (int j = 0; j < 24; ++j) {
            ASSERT_TRUE(offsets.count(kNames[j])) << kNames[j];
            for (int k = 0; k < 3; ++k) EXPECT_NEAR(offsets[kNames[j]][k], sk.offsets[j][k], 1e-6) << kNames[j];
        }
        EXPECT_EQ(checked, frames * 24);
        EXPECT_LT(worst, 0.01) << "worst joint rotation error, degrees (order " << order << ")";
        EXPECT_LT(worst_root, 1e-5);
    }
}
#endif

TEST(BvhWriter, EveryFlushLeavesAValidFileBehind)
{
    const bvh_skeleton sk = smpl_skeleton();
    const std::string path = test_temp_path("stream.bvh");
    bvh_writer *w = nullptr;
    ASSERT_EQ(bvh_writer_open(path.c_str(), &sk, 1.0 / 60.0, BVH_ORDER_ZXY, &w), MOCAP_OK);
    long declared = -1, lines = -1;
    count_frames(slurp(path), &declared, &lines);
    EXPECT_EQ(declared, 0);  // the header alone is already a valid (empty) BVH
    EXPECT_EQ(lines, 0);
    float root[3] = {0, 0.93f, 0};
    float rot[24][4];
    for (auto &q : rot) q[0] = 1, q[1] = q[2] = q[3] = 0;
    for (int f = 1; f <= 5; ++f) {
        ASSERT_EQ(bvh_writer_append(w, root, rot), MOCAP_OK);
        count_frames(slurp(path), &declared, &lines);  // read while the writer is still open
        EXPECT_EQ(declared, f);
        EXPECT_EQ(lines, f);
    }
    bvh_writer_set_flush_every(w, 10);
    for (int f = 0; f < 25; ++f) ASSERT_EQ(bvh_writer_append(w, root, rot), MOCAP_OK);
    count_frames(slurp(path), &declared, &lines);
    EXPECT_EQ(declared, 25);  // 5 + two full batches of 10 flushed; 5 frames still buffered
    EXPECT_GE(lines, 25);
    ASSERT_EQ(bvh_writer_close(w), MOCAP_OK);
    count_frames(slurp(path), &declared, &lines);
    EXPECT_EQ(declared, 30);
    EXPECT_EQ(lines, 30);
}

#if !defined(_WIN32) // Windows: needs fork + RLIMIT_FSIZE for a full disk
// A disk that fills part way: the first write error is returned by every later call with its
// own text (the file and the cause), whatever the thread did in between, and by close.
TEST(BvhWriter, AFailedWriteKeepsItsMessage)
{
    const bvh_skeleton sk = smpl_skeleton();
    const std::string path = test_temp_path("limited.bvh");
    const std::string missing = test_temp_dir() + "/no/such/dir/x.bvh";
    // Room for the header, then a few dozen frames.
    const int code = exit_code_with_file_size_limit(8192, [&]() -> int {
        bvh_writer *w = nullptr;
        if (bvh_writer_open(path.c_str(), &sk, 1.0 / 60.0, BVH_ORDER_ZXY, &w) != MOCAP_OK) return 11;
        float root[3] = {0, 0.93f, 0};
        float rot[24][4];
        for (auto &q : rot) q[0] = 0.5f, q[1] = q[2] = q[3] = 0.5f;
        mocap_status st = MOCAP_OK;
        for (int f = 0; f < 1000 && st == MOCAP_OK; ++f) st = bvh_writer_append(w, root, rot);
        if (st != MOCAP_ERR_IO) return 12;
        const std::string first = mocap_last_error();
        if (first.find("limited.bvh") == std::string::npos) return 13;
        // Something else fails on this thread; the writer's next answer is still its own.
        bvh_writer *other = nullptr;
        if (bvh_writer_open(missing.c_str(), &sk, 1.0 / 60.0, BVH_ORDER_ZXY, &other) == MOCAP_OK) return 14;
        if (bvh_writer_append(w, root, rot) != MOCAP_ERR_IO) return 15;
        if (std::string(mocap_last_error()).find(first) == std::string::npos) return 16;
        bvh_writer_open(missing.c_str(), &sk, 1.0 / 60.0, BVH_ORDER_ZXY, &other);
        if (bvh_writer_close(w) != MOCAP_ERR_IO) return 17;
        if (std::string(mocap_last_error()).find(first) == std::string::npos) return 18;
        return 0;
    });
    EXPECT_EQ(code, 0) << "12: no IO error, 13: file not named, 15/17: error lost, "
                          "16/18: another call's message returned";
}
#endif

TEST(BvhWriter, RefusesBadInputsNamingTheProblem)
{
    bvh_skeleton sk = smpl_skeleton();
    bvh_writer *w = nullptr;
    const std::string missing = test_temp_dir() + "/no/such/dir/x.bvh";
    EXPECT_NE(bvh_writer_open(missing.c_str(), &sk, 1.0 / 60.0, BVH_ORDER_ZXY, &w), MOCAP_OK);
    EXPECT_EQ(w, nullptr);
    EXPECT_NE(std::string(mocap_last_error()).find(missing), std::string::npos) << mocap_last_error();

    const std::string path = test_temp_path("bad.bvh");
    EXPECT_EQ(bvh_writer_open(path.c_str(), &sk, 0.0, BVH_ORDER_ZXY, &w), MOCAP_ERR_INVALID_ARGUMENT);
    sk.parents[4] = 7;  // a parent after its child
    EXPECT_EQ(bvh_writer_open(path.c_str(), &sk, 1.0 / 60.0, BVH_ORDER_ZXY, &w), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("left_knee"), std::string::npos) << mocap_last_error();
    sk = smpl_skeleton();
    std::snprintf(sk.names[3], BVH_NAME_CAP, "spine 1");
    EXPECT_EQ(bvh_writer_open(path.c_str(), &sk, 1.0 / 60.0, BVH_ORDER_ZXY, &w), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_FALSE(fs::exists(path));
}

TEST(BvhWriter, WritesPosesWithTheModelSkeleton)
{
    mocap_model_info info;
    std::memset(&info, 0, sizeof info);
    info.frame_rate = 60;
    bvh_skeleton ref = smpl_skeleton();
    for (int j = 0; j < 24; ++j) {
        std::snprintf(info.joint_names[j], sizeof info.joint_names[j], "%s", kNames[j]);
        info.joint_parents[j] = kParents[j];
        for (int k = 0; k < 3; ++k) info.rest_offsets[j][k] = ref.offsets[j][k];
    }
    bvh_skeleton sk;
    ASSERT_EQ(bvh_skeleton_from_model_info(&info, &sk), MOCAP_OK);
    EXPECT_EQ(sk.joint_count, 24);
    const std::string path = test_temp_path("pose.bvh");
    bvh_writer *w = nullptr;
    ASSERT_EQ(bvh_writer_open(path.c_str(), &sk, 1.0 / info.frame_rate, BVH_ORDER_ZXY, &w), MOCAP_OK);
    mocap_pose pose;
    std::memset(&pose, 0, sizeof pose);
    for (auto &q : pose.joint_rotations) q[0] = 1;
    pose.root_position[1] = 0.93f;
    pose.joint_rotations[18][0] = NAN;  // written as identity, never as "nan"
    ASSERT_EQ(bvh_writer_append_pose(w, &pose), MOCAP_OK);
    ASSERT_EQ(bvh_writer_close(w), MOCAP_OK);
    std::string text = slurp(path);
    EXPECT_EQ(text.find("nan"), std::string::npos);
    EXPECT_NE(text.find("ROOT pelvis"), std::string::npos);
    EXPECT_NE(text.find("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"),
              std::string::npos);
    EXPECT_NE(text.find("Frame Time: 0.01666667"), std::string::npos);
    EXPECT_NE(text.find("\n0 0.93 0 0 0 0"), std::string::npos) << text.substr(text.find("Frame Time"));
}
