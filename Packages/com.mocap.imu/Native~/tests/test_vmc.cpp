// VMC sender: a UDP receiver of the test's own, bound to 127.0.0.1, decodes what the public API
// sends (an OSC decoder written here, independent of src/output/osc_encoder.c): bundle structure, bone
// names and counts, Unity coordinates of a known pose, the rate cap, several destinations, and
// destinations that must fail (nothing is ever sent off this machine). Also the public BVH API.
#include <gtest/gtest.h>

#if defined(_WIN32)
#include <winsock2.h>
#include <ws2tcpip.h>
#define poll WSAPoll
static int close_socket(int fd) { return closesocket((SOCKET)fd); }
#else
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>
static int close_socket(int fd) { return close(fd); }
#endif

#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.h"

extern "C" {
#include "mocap_imu.h"
#include "udp_sender.h"
#include "vmc_sender.h"
}

namespace {

const char *kSmplNames[24] = {"pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee",
                              "spine2", "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot",
                              "neck", "left_collar", "right_collar", "head", "left_shoulder",
                              "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist",
                              "left_hand", "right_hand"};
const int kParents[24] = {-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21};

mocap_model_info smpl_info()
{
    mocap_model_info info;
    std::memset(&info, 0, sizeof info);
    info.frame_rate = 60;
    for (int j = 0; j < 24; ++j) {
        std::snprintf(info.joint_names[j], sizeof info.joint_names[j], "%s", kSmplNames[j]);
        info.joint_parents[j] = kParents[j];
        info.rest_offsets[j][0] = 0.01f * (float)j + (std::strncmp(kSmplNames[j], "left", 4) == 0 ? 0.1f : 0.0f);
        info.rest_offsets[j][1] = j == 0 ? 0.93f : -0.02f * (float)j;
        info.rest_offsets[j][2] = 0.005f * (float)j;
    }
    return info;
}

mocap_pose identity_pose(double t)
{
    mocap_pose p;
    std::memset(&p, 0, sizeof p);
    p.time_s = t;
    for (int j = 0; j < 24; ++j) p.joint_rotations[j][0] = 1.0f;
    return p;
}

struct Message {
    std::string address, tags;
    std::vector<float> f;
    std::vector<int32_t> i;
    std::vector<std::string> s;
};

uint32_t be32(const uint8_t *p) { return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | p[3]; }

bool read_string(const uint8_t *p, size_t n, size_t &at, std::string &out)
{
    size_t end = at;
    while (end < n && p[end]) ++end;
    if (end >= n) return false;
    out.assign((const char *)p + at, end - at);
    at = (end + 4) & ~size_t(3);
    return at <= n;
}

bool decode_message(const uint8_t *p, size_t n, Message &m)
{
    size_t at = 0;
    if (!read_string(p, n, at, m.address) || !read_string(p, n, at, m.tags) || m.tags.empty() || m.tags[0] != ',')
        return false;
    for (char t : m.tags.substr(1)) {
        if (t == 's') {
            std::string s;
            if (!read_string(p, n, at, s)) return false;
            m.s.push_back(s);
        } else {
            if (at + 4 > n) return false;
            uint32_t v = be32(p + at);
            at += 4;
            if (t == 'i') m.i.push_back((int32_t)v);
            else if (t == 'f') { float f; std::memcpy(&f, &v, 4); m.f.push_back(f); }
            else return false;
        }
    }
    return at == n;
}

// One bundle (no nesting) -> its messages; false when the datagram is not a well-formed bundle.
bool decode_bundle(const std::vector<uint8_t> &d, std::vector<Message> &out)
{
    if (d.size() < 16 || std::memcmp(d.data(), "#bundle\0", 8) != 0) return false;
    size_t at = 16;
    while (at < d.size()) {
        if (at + 4 > d.size()) return false;
        uint32_t size = be32(d.data() + at);
        at += 4;
        if (size % 4 || at + size > d.size()) return false;
        Message m;
        if (!decode_message(d.data() + at, size, m)) return false;
        out.push_back(m);
        at += size;
    }
    return at == d.size();
}

struct Receiver {
    int fd = -1;
    int port = 0;
    explicit Receiver(int family = AF_INET)
    {
#if defined(_WIN32)
        WSADATA wsa; // reference-counted; the receiver may open before the sender started Winsock
        if (WSAStartup(MAKEWORD(2, 2), &wsa) != 0) return;
#endif
        fd = (int)socket(family, SOCK_DGRAM, 0);
        if (fd < 0) return;
        int big = 4 << 20;
        setsockopt(fd, SOL_SOCKET, SO_RCVBUF, (const char *)&big, sizeof big);
        if (family == AF_INET) {
            sockaddr_in a{};
            a.sin_family = AF_INET;
            a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);  // loopback only
            if (bind(fd, (sockaddr *)&a, sizeof a) != 0) { close_socket(fd); fd = -1; return; }
            socklen_t len = sizeof a;
            getsockname(fd, (sockaddr *)&a, &len);
            port = ntohs(a.sin_port);
        } else {
            sockaddr_in6 a{};
            a.sin6_family = AF_INET6;
            a.sin6_addr = in6addr_loopback;
            if (bind(fd, (sockaddr *)&a, sizeof a) != 0) { close_socket(fd); fd = -1; return; }
            socklen_t len = sizeof a;
            getsockname(fd, (sockaddr *)&a, &len);
            port = ntohs(a.sin6_port);
        }
    }
    ~Receiver() { if (fd >= 0) close_socket(fd); }
    // Every datagram that arrives within timeout_ms of the previous one.
    std::vector<std::vector<uint8_t>> receive_all(int timeout_ms = 300)
    {
        std::vector<std::vector<uint8_t>> out;
        for (;;) {
            pollfd p{};
            p.fd = fd;
            p.events = POLLIN;
            if (poll(&p, 1, timeout_ms) <= 0) break;
            std::vector<uint8_t> buf(65536);
            const auto n = recv(fd, (char *)buf.data(), (int)buf.size(), 0);
            if (n < 0) break;
            buf.resize((size_t)n);
            out.push_back(buf);
        }
        return out;
    }
};

mocap_vmc *open_vmc(const std::string &dest, float rate = 60.0f)
{
    mocap_vmc_options o;
    mocap_vmc_options_defaults(&o);
    o.max_rate_hz = rate;
    mocap_vmc *v = nullptr;
    EXPECT_EQ(mocap_vmc_open(dest.c_str(), &o, &v), MOCAP_OK) << mocap_last_error();
    return v;
}

void rotate(const double q[4], const double v[3], double out[3])  // q = (w,x,y,z)
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double m[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                   2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                   2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)};
    for (int r = 0; r < 3; ++r) out[r] = m[3 * r] * v[0] + m[3 * r + 1] * v[1] + m[3 * r + 2] * v[2];
}

}  // namespace

TEST(Vmc, KnownPoseArrivesAsOneBundleInUnityCoordinates)
{
    Receiver rx;
    ASSERT_GE(rx.fd, 0);
    mocap_model_info info = smpl_info();
    mocap_pose pose = identity_pose(12.25);
    pose.root_position[0] = 1.0f;
    pose.root_position[1] = 1.13f;
    pose.root_position[2] = 2.0f;
    const float h = std::sqrt(0.5f);
    float pelvis[4] = {h, 0, h, 0};   // 90 degrees about model +Y
    float elbow[4] = {0.8f, 0.6f, 0, 0};  // about model +X
    float knee[4] = {0.5f, 0.5f, 0.5f, 0.5f};
    std::memcpy(pose.joint_rotations[0], pelvis, sizeof pelvis);
    std::memcpy(pose.joint_rotations[18], elbow, sizeof elbow);
    std::memcpy(pose.joint_rotations[4], knee, sizeof knee);

    mocap_vmc *v = open_vmc("127.0.0.1:" + std::to_string(rx.port));
    ASSERT_NE(v, nullptr);
    ASSERT_EQ(mocap_vmc_send_pose(v, &info, &pose), MOCAP_OK) << mocap_last_error();
    auto datagrams = rx.receive_all();
    ASSERT_EQ(datagrams.size(), 1u);
    std::vector<Message> msgs;
    ASSERT_TRUE(decode_bundle(datagrams[0], msgs));
    ASSERT_EQ(msgs.size(), 3u + 22u);
    EXPECT_EQ(msgs[0].address, "/VMC/Ext/OK");
    EXPECT_EQ(msgs[0].i, (std::vector<int32_t>{1, 3, 0}));
    EXPECT_EQ(msgs[1].address, "/VMC/Ext/T");
    ASSERT_EQ(msgs[1].f.size(), 1u);
    EXPECT_FLOAT_EQ(msgs[1].f[0], 12.25f);
    EXPECT_EQ(msgs[2].address, "/VMC/Ext/Root/Pos");
    EXPECT_EQ(msgs[2].tags, ",sfffffff");
    ASSERT_EQ(msgs[2].s, std::vector<std::string>{"root"});
    // Root on the floor under the pelvis, X mirrored: (1, 1.13 - 0.93, 2) -> (-1, 0.2, 2).
    std::vector<float> root_expected = {-1.0f, 0.2f, 2.0f, 0, 0, 0, 1};
    for (int k = 0; k < 7; ++k) EXPECT_NEAR(msgs[2].f[k], root_expected[k], 1e-6) << k;

    const char *expected_bones[22] = {"Hips", "LeftUpperLeg", "RightUpperLeg", "Spine", "LeftLowerLeg",
                                      "RightLowerLeg", "Chest", "LeftFoot", "RightFoot", "UpperChest",
                                      "LeftToes", "RightToes", "Neck", "LeftShoulder", "RightShoulder",
                                      "Head", "LeftUpperArm", "RightUpperArm", "LeftLowerArm",
                                      "RightLowerArm", "LeftHand", "RightHand"};
    std::map<std::string, const Message *> bones;
    for (int b = 0; b < 22; ++b) {
        const Message &m = msgs[3 + b];
        EXPECT_EQ(m.address, "/VMC/Ext/Bone/Pos");
        EXPECT_EQ(m.tags, ",sfffffff");
        ASSERT_EQ(m.s.size(), 1u);
        EXPECT_EQ(m.s[0], expected_bones[b]);
        bones[m.s[0]] = &m;
        // Local position = the joint's rest offset, X mirrored.
        int j = b < 22 ? b : 0;  // the 22 mapped joints are SMPL joints 0..21 in order
        EXPECT_FLOAT_EQ(m.f[0], -info.rest_offsets[j][0]) << m.s[0];
        EXPECT_FLOAT_EQ(m.f[1], info.rest_offsets[j][1]) << m.s[0];
        EXPECT_FLOAT_EQ(m.f[2], info.rest_offsets[j][2]) << m.s[0];
    }
    EXPECT_EQ(bones.size(), 22u);  // each bone once
    // (w,x,y,z) -> Unity (x,-y,-z,w).
    auto rot = [&](const char *b) { return std::vector<float>(bones[b]->f.begin() + 3, bones[b]->f.end()); };
    EXPECT_EQ(rot("Hips"), (std::vector<float>{0, -h, 0, h}));
    EXPECT_EQ(rot("LeftLowerArm"), (std::vector<float>{0.6f, -0.0f, -0.0f, 0.8f}));
    EXPECT_EQ(rot("LeftLowerLeg"), (std::vector<float>{0.5f, -0.5f, -0.5f, 0.5f}));
    EXPECT_EQ(rot("Spine"), (std::vector<float>{0, -0.0f, -0.0f, 1}));

    mocap_vmc_stats st;
    ASSERT_EQ(mocap_vmc_get_stats(v, &st), MOCAP_OK);
    EXPECT_EQ(st.bundles_sent, 1u);
    EXPECT_EQ(st.bones_per_bundle, 22u);
    EXPECT_EQ(st.last_bundle_size, datagrams[0].size());
    mocap_vmc_close(v);
}

TEST(Vmc, MirroredRotationRotatesMirroredVectors)
{
    // The conversion is right iff mirror(R v) == R_unity mirror(v) for any rotation and vector.
    for (int trial = 0; trial < 50; ++trial) {
        double q[4] = {std::cos(trial * 0.7), std::sin(trial * 1.3), std::cos(trial * 2.1), std::sin(trial * 0.3 + 1)};
        double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        for (double &c : q) c /= n;
        float qf[4] = {(float)q[0], (float)q[1], (float)q[2], (float)q[3]}, u[4];
        vmc_rotation_to_unity(qf, u);
        double qu[4] = {u[3], u[0], u[1], u[2]};
        double v[3] = {0.3, -0.7, 1.1}, rv[3], mv[3] = {-v[0], v[1], v[2]}, urv[3];
        rotate(q, v, rv);
        rotate(qu, mv, urv);
        EXPECT_NEAR(urv[0], -rv[0], 1e-5);
        EXPECT_NEAR(urv[1], rv[1], 1e-5);
        EXPECT_NEAR(urv[2], rv[2], 1e-5);
    }
    float bad[4] = {0, 0, 0, 0}, nan_q[4] = {NAN, 0, 0, 1}, u[4];
    vmc_rotation_to_unity(bad, u);
    EXPECT_EQ(u[3], 1.0f);
    vmc_rotation_to_unity(nan_q, u);
    EXPECT_EQ(u[3], 1.0f);
    EXPECT_EQ(u[0], 0.0f);
}

TEST(Vmc, RateCapSkipsPosesSoAtMostNPerSecondAreSent)
{
    Receiver rx;
    ASSERT_GE(rx.fd, 0);
    mocap_model_info info = smpl_info();
    struct Case { float cap; int expected_min, expected_max; } cases[] = {
        {25.0f, 49, 51}, {60.0f, 120, 120}, {0.0f, 120, 120}, {200.0f, 120, 120}, {10.0f, 19, 21}};
    for (const Case &c : cases) {
        mocap_vmc *v = open_vmc("127.0.0.1:" + std::to_string(rx.port), c.cap);
        ASSERT_NE(v, nullptr);
        int ok = 0, skipped = 0;
        for (int k = 0; k < 120; ++k) {  // 2 s of 60 Hz poses
            mocap_pose p = identity_pose(100.0 + k / 60.0);
            mocap_status s = mocap_vmc_send_pose(v, &info, &p);
            if (s == MOCAP_OK) ok++;
            else if (s == MOCAP_ERR_NO_DATA) skipped++;
            else ADD_FAILURE() << mocap_status_name(s) << " " << mocap_last_error();
        }
        auto got = rx.receive_all(200);
        EXPECT_GE(ok, c.expected_min) << "cap " << c.cap;
        EXPECT_LE(ok, c.expected_max) << "cap " << c.cap;
        EXPECT_EQ(ok + skipped, 120);
        EXPECT_EQ((int)got.size(), ok) << "cap " << c.cap;
        mocap_vmc_stats st;
        mocap_vmc_get_stats(v, &st);
        EXPECT_EQ(st.bundles_sent, (uint64_t)ok);
        EXPECT_EQ(st.skipped_rate, (uint64_t)skipped);
        // No one-second window of pose time holds more than cap + 1 bundles.
        if (c.cap > 0) {
            std::vector<float> times;
            for (auto &d : got) {
                std::vector<Message> m;
                ASSERT_TRUE(decode_bundle(d, m));
                times.push_back(m[1].f[0]);
            }
            for (size_t a = 0; a < times.size(); ++a) {
                size_t b = a;
                while (b < times.size() && times[b] < times[a] + 1.0f - 1e-4f) ++b;
                EXPECT_LE(b - a, (size_t)c.cap + 1) << "cap " << c.cap;
            }
        }
        mocap_vmc_close(v);
    }
}

TEST(Vmc, SeveralCharactersToSeveralPorts)
{
    Receiver a, b;
    ASSERT_GE(a.fd, 0);
    ASSERT_GE(b.fd, 0);
    mocap_model_info info = smpl_info();
    mocap_vmc *va = open_vmc("127.0.0.1:" + std::to_string(a.port));
    mocap_vmc *vb = open_vmc("localhost:" + std::to_string(b.port));
    ASSERT_TRUE(va && vb);
    for (int k = 0; k < 5; ++k) {
        mocap_pose p = identity_pose(k / 60.0);
        p.root_position[0] = 1.0f;
        mocap_pose q = identity_pose(k / 60.0);
        q.root_position[0] = 2.0f;
        EXPECT_EQ(mocap_vmc_send_pose(va, &info, &p), MOCAP_OK);
        EXPECT_EQ(mocap_vmc_send_pose(vb, &info, &q), MOCAP_OK);
    }
    auto ga = a.receive_all(), gb = b.receive_all();
    ASSERT_EQ(ga.size(), 5u);
    ASSERT_EQ(gb.size(), 5u);
    std::vector<Message> ma, mb;
    ASSERT_TRUE(decode_bundle(ga[0], ma));
    ASSERT_TRUE(decode_bundle(gb[0], mb));
    EXPECT_FLOAT_EQ(ma[2].f[0], -1.0f);
    EXPECT_FLOAT_EQ(mb[2].f[0], -2.0f);
    mocap_vmc_close(va);
    mocap_vmc_close(vb);
}

TEST(Vmc, Ipv6LoopbackDestination)
{
    Receiver rx(AF_INET6);
    if (rx.fd < 0) GTEST_SKIP() << "no IPv6 loopback here";
    mocap_model_info info = smpl_info();
    mocap_vmc *v = open_vmc("[::1]:" + std::to_string(rx.port));
    ASSERT_NE(v, nullptr);
    mocap_pose p = identity_pose(1.0);
    EXPECT_EQ(mocap_vmc_send_pose(v, &info, &p), MOCAP_OK) << mocap_last_error();
    auto got = rx.receive_all();
    ASSERT_EQ(got.size(), 1u);
    std::vector<Message> m;
    EXPECT_TRUE(decode_bundle(got[0], m));
    mocap_vmc_close(v);
}

#if !defined(_WIN32) // Windows: reads /proc/self/fd
TEST(Vmc, SocketIsNotInheritedByStartedPrograms)
{
    Receiver rx(AF_INET);
    ASSERT_GE(rx.fd, 0);
    udp_sender *u = nullptr;
    const std::string dest = "127.0.0.1:" + std::to_string(rx.port);
    OpenedDescriptors d = descriptors_opened_by([&] {
        ASSERT_EQ(udp_sender_open(dest.c_str(), 0, &u), MOCAP_OK) << mocap_last_error();
    });
    ASSERT_NE(u, nullptr);
    EXPECT_EQ(d.opened.size(), 1u);
    EXPECT_TRUE(d.inheritable.empty()) << "a program the editor starts would hold our port";
    EXPECT_EQ(udp_sender_send(u, "x", 1), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(rx.receive_all().size(), 1u);
    udp_sender_close(u);
}
#endif

TEST(Vmc, DestinationsParseAndDefaultToLoopback)
{
    char host[256];
    int port = 0;
    ASSERT_EQ(udp_parse_destination(nullptr, 39539, host, sizeof host, &port), MOCAP_OK);
    EXPECT_STREQ(host, "127.0.0.1");
    EXPECT_EQ(port, 39539);
    ASSERT_EQ(udp_parse_destination("localhost", 39539, host, sizeof host, &port), MOCAP_OK);
    EXPECT_STREQ(host, "localhost");
    EXPECT_EQ(port, 39539);
    ASSERT_EQ(udp_parse_destination("[::1]:9000", 39539, host, sizeof host, &port), MOCAP_OK);
    EXPECT_STREQ(host, "::1");
    EXPECT_EQ(port, 9000);
    ASSERT_EQ(udp_parse_destination("::1", 39539, host, sizeof host, &port), MOCAP_OK);
    EXPECT_STREQ(host, "::1");
    EXPECT_EQ(port, 39539);
    udp_sender *s = nullptr;
    ASSERT_EQ(udp_sender_open(nullptr, 0, &s), MOCAP_OK) << mocap_last_error();
    EXPECT_STREQ(udp_sender_address(s), "127.0.0.1:39539");
    EXPECT_TRUE(udp_sender_is_loopback(s));
    udp_sender_close(s);
    mocap_vmc_options o;
    ASSERT_EQ(mocap_vmc_options_defaults(&o), MOCAP_OK);
    EXPECT_EQ(o.max_rate_hz, 60.0f);
    EXPECT_EQ(o.allow_remote, 0);
}

TEST(Vmc, BadDestinationsFailNamingThem)
{
    struct Case { const char *dest; mocap_status status; } cases[] = {
        {"127.0.0.1:0", MOCAP_ERR_INVALID_ARGUMENT},
        {"127.0.0.1:70000", MOCAP_ERR_INVALID_ARGUMENT},
        {"127.0.0.1:port", MOCAP_ERR_INVALID_ARGUMENT},
        {":39539", MOCAP_ERR_INVALID_ARGUMENT},
        {"[::1:39539", MOCAP_ERR_INVALID_ARGUMENT},
        {"no-such-host.invalid:39539", MOCAP_ERR_NOT_FOUND},
        // Not loopback and allow_remote not set: refused before any socket exists.
        {"192.0.2.1:39539", MOCAP_ERR_PERMISSION},
        {"[2001:db8::1]:39539", MOCAP_ERR_PERMISSION},
    };
    for (const Case &c : cases) {
        mocap_vmc *v = reinterpret_cast<mocap_vmc *>(0x1);
        mocap_status s = mocap_vmc_open(c.dest, nullptr, &v);
        EXPECT_EQ(s, c.status) << c.dest << ": " << mocap_last_error();
        EXPECT_EQ(v, nullptr);
        EXPECT_NE(std::string(mocap_last_error()).find(c.dest), std::string::npos)
            << c.dest << ": " << mocap_last_error();
    }
    mocap_vmc_options o;
    mocap_vmc_options_defaults(&o);
    o.struct_size = 3;
    mocap_vmc *v = nullptr;
    EXPECT_EQ(mocap_vmc_open("127.0.0.1:39539", &o, &v), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(mocap_vmc_send_pose(nullptr, nullptr, nullptr), MOCAP_ERR_INVALID_ARGUMENT);
}

TEST(Vmc, ModelInfoWithoutSmplNamesIsRefused)
{
    Receiver rx;
    mocap_model_info info = smpl_info();
    for (int j = 0; j < 24; ++j) std::snprintf(info.joint_names[j], 32, "joint%d", j);
    mocap_vmc *v = open_vmc("127.0.0.1:" + std::to_string(rx.port));
    mocap_pose p = identity_pose(0);
    EXPECT_EQ(mocap_vmc_send_pose(v, &info, &p), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_TRUE(rx.receive_all(100).empty());
    mocap_vmc_close(v);
}

TEST(BvhExport, PublicApiWritesFramesAndFrameTime)
{
    mocap_model_info info = smpl_info();
    const std::string path = test_temp_path("export.bvh");
    mocap_bvh_options o;
    ASSERT_EQ(mocap_bvh_options_defaults(&o), MOCAP_OK);
    o.frame_rate = 30.0f;
    mocap_bvh_writer *w = nullptr;
    ASSERT_EQ(mocap_bvh_open(path.c_str(), &info, &o, &w), MOCAP_OK) << mocap_last_error();
    for (int k = 0; k < 7; ++k) {
        mocap_pose p = identity_pose(k / 30.0);
        p.root_position[1] = 0.93f;
        ASSERT_EQ(mocap_bvh_append(w, &p), MOCAP_OK);
    }
    EXPECT_EQ(mocap_bvh_frames(w), 7u);
    ASSERT_EQ(mocap_bvh_close(w), MOCAP_OK);
    std::ifstream f(path);
    std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("ROOT pelvis"), std::string::npos);
    EXPECT_NE(text.find("Frames: 7"), std::string::npos) << text.substr(0, 200);
    EXPECT_NE(text.find("Frame Time: 0.0333333"), std::string::npos);
    // Bad inputs name the problem.
    o.rotation_order = 7;
    EXPECT_EQ(mocap_bvh_open(path.c_str(), &info, &o, &w), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(mocap_bvh_open("/nonexistent-dir/x.bvh", &info, nullptr, &w), MOCAP_OK);
    EXPECT_NE(std::string(mocap_last_error()).find("/nonexistent-dir/x.bvh"), std::string::npos);
}

// One SMPL -> humanoid map: the public one (which C# reads) is the VMC stream's, joint for joint,
// and the two hand end points drive no bone.
TEST(Vmc, PublicHumanoidMapIsTheOneTheStreamUses)
{
    for (int j = 0; j < VMC_BONE_COUNT; ++j) {
        const char *joint = nullptr, *bone = nullptr;
        vmc_bone_pair(j, &joint, &bone);
        ASSERT_NE(mocap_humanoid_bone_name(j), nullptr) << j;
        EXPECT_STREQ(mocap_humanoid_bone_name(j), bone) << joint;
        EXPECT_STREQ(vmc_bone_name(joint), bone) << joint;
    }
    EXPECT_STREQ(mocap_humanoid_bone_name(0), "Hips");
    EXPECT_STREQ(mocap_humanoid_bone_name(13), "LeftShoulder");   // left_collar
    EXPECT_STREQ(mocap_humanoid_bone_name(16), "LeftUpperArm");   // left_shoulder
    EXPECT_STREQ(mocap_humanoid_bone_name(11), "RightToes");      // right_foot
    EXPECT_EQ(mocap_humanoid_bone_name(22), nullptr);             // left_hand: the knuckles
    EXPECT_EQ(mocap_humanoid_bone_name(23), nullptr);
    EXPECT_EQ(mocap_humanoid_bone_name(-1), nullptr);
    EXPECT_EQ(mocap_humanoid_bone_name(MOCAP_JOINT_COUNT), nullptr);
    EXPECT_EQ(vmc_bone_name("left_hand"), nullptr);
    EXPECT_EQ(vmc_bone_name("not_a_joint"), nullptr);
}
