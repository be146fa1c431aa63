// The pose model's geometry done by the engine (src/pose/network_geometry.c), by the properties
// the model relies on: heading removal, residuals on the rest pose and on the measured bones,
// the mirror average and the mask. Its agreement with the exported graphs, number for number, is
// checked through the real ONNX Runtime in training/tests/test_network_geometry.py.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

extern "C" {
#include "mocap_math.h"
#include "network_geometry.h"
#include "smpl_skeleton.h"
}

namespace {

// pelvis, left_wrist, right_wrist, left_shin, right_shin, head; the wrists anchor the hands
const int kSensors = 6;
const int kMirrorSensors[kSensors] = {0, 2, 1, 4, 3, 5};
const int kAnchors[kSensors] = {0, 22, 23, 4, 5, 15};
const int kMirrorJoints[GEOMETRY_JOINTS] = {0,  2,  1,  3,  5,  4,  6,  8,  7,  9,  11, 10,
                                            12, 14, 13, 15, 17, 16, 19, 18, 21, 20, 23, 22};
const float kReflect[3] = {-1.0f, 1.0f, 1.0f};

int parents[GEOMETRY_JOINTS];

network_geometry make(int masked, int mirror, const int *anchors = kAnchors)
{
    for (int j = 0; j < GEOMETRY_JOINTS; ++j) parents[j] = smpl_joint_parent(j);
    network_geometry g;
    EXPECT_EQ(network_geometry_init(&g, kSensors, 0, masked, mirror, 30.0f, kMirrorSensors,
                                    kMirrorJoints, parents, anchors),
              MOCAP_OK)
        << mocap_last_error();
    return g;
}

void random_rotation(mocap_rng *rng, float out[9])
{
    double q[4], m[9];
    mocap_rng_rotation(rng, q);
    quat_to_mat3(m, q);
    for (int e = 0; e < 9; ++e) out[e] = (float)m[e];
}

void yaw(float out[9], double angle)
{
    double m[9];
    mat3_rotation_y(m, angle);
    for (int e = 0; e < 9; ++e) out[e] = (float)m[e];
}

void mul(float out[9], const float a[9], const float b[9])
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            float s = 0.0f;
            for (int k = 0; k < 3; ++k) s += a[i * 3 + k] * b[k * 3 + j];
            out[i * 3 + j] = s;
        }
}

struct Frame {
    float orientation[kSensors * 9];
    float acceleration[kSensors * 3];
    float mask[kSensors];
};

Frame random_frame(uint64_t seed)
{
    mocap_rng rng;
    mocap_rng_seed(&rng, seed);
    Frame f;
    for (int k = 0; k < kSensors; ++k) {
        random_rotation(&rng, f.orientation + k * 9);
        for (int i = 0; i < 3; ++i) f.acceleration[k * 3 + i] = (float)(5.0 * mocap_rng_gaussian(&rng));
        f.mask[k] = 1.0f;
    }
    return f;
}

struct Pose {
    float rotations[GEOMETRY_JOINTS * 9];
    float velocity[3];
    float contact[2];
};

// The geometry around a network that answers `output` on every row.
Pose run(const network_geometry &g, const Frame &f, const std::vector<float> &output,
         std::vector<float> *features = nullptr)
{
    const int rows = network_geometry_rows(&g);
    std::vector<float> feat((size_t)rows * g.features, -99.0f), out;
    geometry_row row[2];
    network_geometry_features(&g, f.orientation, f.acceleration, g.masked ? f.mask : nullptr,
                              feat.data(), (size_t)g.features, row);
    for (int r = 0; r < rows; ++r) out.insert(out.end(), output.begin(), output.end());
    Pose p;
    network_geometry_outputs(&g, out.data(), GEOMETRY_OUTPUTS, row, p.rotations, p.velocity,
                             p.contact);
    if (features) *features = feat;
    return p;
}

// global rotation of each joint from the local ones (joint 0 global)
void globals(const Pose &p, float out[GEOMETRY_JOINTS][9])
{
    for (int e = 0; e < 9; ++e) out[0][e] = p.rotations[e];
    for (int j = 1; j < GEOMETRY_JOINTS; ++j) mul(out[j], out[parents[j]], p.rotations + j * 9);
}

double max_diff(const float *a, const float *b, int n)
{
    double d = 0.0;
    for (int i = 0; i < n; ++i) d = std::fmax(d, std::fabs((double)a[i] - (double)b[i]));
    return d;
}

const std::vector<float> kZero(GEOMETRY_OUTPUTS, 0.0f);

}  // namespace

TEST(NetworkGeometry, RefusesDescriptionsItCannotFollow)
{
    for (int j = 0; j < GEOMETRY_JOINTS; ++j) parents[j] = smpl_joint_parent(j);
    network_geometry g;
    EXPECT_EQ(network_geometry_init(&g, kSensors, -1, 0, 0, 30.0f, nullptr, nullptr, parents, kAnchors),
              MOCAP_ERR_FORMAT);
    EXPECT_NE(std::string(mocap_last_error()).find("pelvis"), std::string::npos);
    const int not_a_pairing[kSensors] = {0, 2, 2, 4, 3, 5};
    EXPECT_EQ(network_geometry_init(&g, kSensors, 0, 0, 1, 30.0f, not_a_pairing, kMirrorJoints,
                                    parents, kAnchors),
              MOCAP_ERR_FORMAT);
    const int pelvis_swapped[kSensors] = {5, 2, 1, 4, 3, 0};
    EXPECT_EQ(network_geometry_init(&g, kSensors, 0, 0, 1, 30.0f, pelvis_swapped, kMirrorJoints,
                                    parents, kAnchors),
              MOCAP_ERR_FORMAT);
    const int out_of_range[kSensors] = {0, 22, 24, 4, 5, 15};
    EXPECT_EQ(network_geometry_init(&g, kSensors, 0, 0, 0, 30.0f, nullptr, nullptr, parents, out_of_range),
              MOCAP_ERR_FORMAT);
    EXPECT_EQ(network_geometry_init(&g, kSensors, 0, 0, 0, 0.0f, nullptr, nullptr, parents, kAnchors),
              MOCAP_ERR_FORMAT);
    int shuffled[GEOMETRY_JOINTS];
    for (int j = 0; j < GEOMETRY_JOINTS; ++j) shuffled[j] = parents[j];
    shuffled[4] = 7;  // a child before its parent
    EXPECT_EQ(network_geometry_init(&g, kSensors, 0, 0, 0, 30.0f, nullptr, nullptr, shuffled, kAnchors),
              MOCAP_ERR_FORMAT);
    // the features of six sensors: 6 x 12 + 5 x 12, and the mask
    EXPECT_EQ(make(0, 0).features, 132);
    EXPECT_EQ(make(1, 1).features, 138);
    const network_geometry plain = make(0, 0), mirrored = make(0, 1);
    const int same_bone[kSensors] = {0, 22, 22, 4, 5, 0};  // the later sensor of a bone wins
    const network_geometry shared = make(0, 0, same_bone);
    ASSERT_EQ(shared.anchored, 3);
    EXPECT_EQ(shared.anchor_joint[0], 22);
    EXPECT_EQ(shared.anchor_sensor[0], 2);
    EXPECT_EQ(network_geometry_rows(&plain), 1);
    EXPECT_EQ(network_geometry_rows(&mirrored), 2);
}

TEST(NetworkGeometry, ZeroResidualsGiveTheRestPoseUnderTheMeasuredPelvis)
{
    const network_geometry g = make(0, 0, std::vector<int>(kSensors, 0).data());
    Frame f = random_frame(1);
    float pelvis[9];
    yaw(pelvis, 0.7);  // upright, turned
    for (int e = 0; e < 9; ++e) f.orientation[e] = pelvis[e];
    const Pose p = run(g, f, kZero);
    EXPECT_LT(max_diff(p.rotations, pelvis, 9), 1e-6);
    const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int j = 1; j < GEOMETRY_JOINTS; ++j)
        EXPECT_LT(max_diff(p.rotations + j * 9, identity, 9), 1e-7) << "joint " << j;
    EXPECT_FLOAT_EQ(p.contact[0], 0.5f);
    EXPECT_FLOAT_EQ(p.velocity[2], 0.0f);
}

TEST(NetworkGeometry, TurningTheWholeBodyChangesNoFeatureAndTurnsPelvisAndVelocity)
{
    const network_geometry g = make(0, 0);
    const Frame f = random_frame(2);
    Frame turned = f;
    float ry[9];
    yaw(ry, -2.1);
    for (int k = 0; k < kSensors; ++k) {
        mul(turned.orientation + k * 9, ry, f.orientation + k * 9);
        for (int i = 0; i < 3; ++i)
            turned.acceleration[k * 3 + i] = ry[i * 3 + 0] * f.acceleration[k * 3 + 0] +
                                             ry[i * 3 + 1] * f.acceleration[k * 3 + 1] +
                                             ry[i * 3 + 2] * f.acceleration[k * 3 + 2];
    }
    std::vector<float> out(GEOMETRY_OUTPUTS);
    for (int i = 0; i < GEOMETRY_OUTPUTS; ++i) out[i] = 0.3f * std::sin(1.7f * i);
    std::vector<float> a, b;
    const Pose p = run(g, f, out, &a), q = run(g, turned, out, &b);
    EXPECT_LT(max_diff(a.data(), b.data(), g.features), 2e-5);
    float expected[9];
    mul(expected, ry, p.rotations);
    EXPECT_LT(max_diff(q.rotations, expected, 9), 2e-5);
    for (int j = 1; j < GEOMETRY_JOINTS; ++j)
        EXPECT_LT(max_diff(q.rotations + j * 9, p.rotations + j * 9, 9), 2e-5) << "joint " << j;
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(q.velocity[i], ry[i * 3] * p.velocity[0] + ry[i * 3 + 1] * p.velocity[1] + ry[i * 3 + 2] * p.velocity[2], 2e-5);
}

TEST(NetworkGeometry, AnchoredBonesReproduceTheMeasuredOrientationsAtZeroResidual)
{
    const network_geometry g = make(0, 0);
    ASSERT_EQ(g.anchored, 5);  // every sensor but the pelvis
    const Frame f = random_frame(3);
    std::vector<float> out(GEOMETRY_OUTPUTS, 0.0f);
    for (int j = 1; j < GEOMETRY_JOINTS; ++j)  // the unmeasured joints bend
        for (int e = 0; e < 6; ++e) out[j * 6 + e] = 0.2f * std::cos(0.9f * (j * 6 + e));
    for (int k = 1; k < kSensors; ++k)
        for (int e = 0; e < 6; ++e) out[kAnchors[k] * 6 + e] = 0.0f;
    const Pose p = run(g, f, out);
    float global[GEOMETRY_JOINTS][9];
    globals(p, global);
    for (int k = 1; k < kSensors; ++k)
        EXPECT_LT(max_diff(global[kAnchors[k]], f.orientation + k * 9, 9), 3e-5) << "sensor " << k;
    // and not where the network bends them away from the measurement
    out[22 * 6 + 1] = 0.5f;
    const Pose bent = run(g, f, out);
    globals(bent, global);
    EXPECT_GT(max_diff(global[22], f.orientation + 9, 9), 0.05);
}

TEST(NetworkGeometry, TheMirrorAverageIsMirrorEquivariant)
{
    const network_geometry g = make(0, 1);
    ASSERT_EQ(network_geometry_rows(&g), 2);
    const Frame f = random_frame(4);
    Frame mirrored = f;  // the mirror image: sides swapped, reflected in the sagittal plane
    for (int k = 0; k < kSensors; ++k) {
        const int m = kMirrorSensors[k];
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j)
                mirrored.orientation[k * 9 + i * 3 + j] = f.orientation[m * 9 + i * 3 + j] * kReflect[i] * kReflect[j];
            mirrored.acceleration[k * 3 + i] = f.acceleration[m * 3 + i] * kReflect[i];
        }
    }
    std::vector<float> out(GEOMETRY_OUTPUTS);
    for (int i = 0; i < GEOMETRY_OUTPUTS; ++i) out[i] = 0.25f * std::sin(0.37f * i + 1.0f);
    out[GEOMETRY_OUTPUTS - 2] = 1.5f;  // the left foot planted, the right not
    out[GEOMETRY_OUTPUTS - 1] = -2.0f;
    const Pose p = run(g, f, out), q = run(g, mirrored, out);
    for (int j = 0; j < GEOMETRY_JOINTS; ++j) {
        float expected[9];
        for (int i = 0; i < 3; ++i)
            for (int c = 0; c < 3; ++c)
                expected[i * 3 + c] = p.rotations[kMirrorJoints[j] * 9 + i * 3 + c] * kReflect[i] * kReflect[c];
        EXPECT_LT(max_diff(q.rotations + j * 9, expected, 9), 2e-5) << "joint " << j;
    }
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(q.velocity[i], p.velocity[i] * kReflect[i], 1e-5);
    EXPECT_NEAR(q.contact[0], p.contact[1], 1e-6);
    EXPECT_NEAR(p.contact[0], p.contact[1], 1e-6);  // both rows' left and right averaged
    // every output a rotation
    for (int j = 0; j < GEOMETRY_JOINTS; ++j) {
        double m[9], rt[9];
        for (int e = 0; e < 9; ++e) m[e] = p.rotations[j * 9 + e];
        mat3_multiply_transposed(rt, m, m);
        EXPECT_NEAR(rt[0] + rt[4] + rt[8], 3.0, 1e-5);
        EXPECT_NEAR(m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                        m[2] * (m[3] * m[7] - m[4] * m[6]),
                    1.0, 1e-5);
    }
}

TEST(NetworkGeometry, AMissingSensorSaysNothingAndItsBoneRestsOnThePrediction)
{
    const network_geometry g = make(1, 0);
    Frame f = random_frame(5);
    const int wrist = 1;
    f.mask[wrist] = 0.0f;
    for (int e = 0; e < 9; ++e) f.orientation[wrist * 9 + e] = 0.0f;  // the engine feeds zeros
    for (int i = 0; i < 3; ++i) f.acceleration[wrist * 3 + i] = 0.0f;
    std::vector<float> feat;
    const Pose p = run(g, f, kZero, &feat);
    const int n = kSensors;
    for (int e = 0; e < 9; ++e) EXPECT_EQ(feat[wrist * 9 + e], 0.0f);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(feat[9 * n + wrist * 3 + i], 0.0f);
    const int rel = 12 * n + (wrist - 1) * 9;  // the wrist relative to the pelvis
    for (int e = 0; e < 9; ++e) EXPECT_EQ(feat[rel + e], 0.0f);
    EXPECT_EQ(feat[g.features - n + wrist], 0.0f);
    EXPECT_EQ(feat[g.features - n + 0], 1.0f);
    EXPECT_NE(feat[2 * 9], 0.0f);  // the other wrist still speaks
    // with zero residuals the missing wrist's hand keeps the rest pose under its parent
    const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    EXPECT_LT(max_diff(p.rotations + 22 * 9, identity, 9), 1e-6);
    float global[GEOMETRY_JOINTS][9];
    globals(p, global);
    EXPECT_LT(max_diff(global[23], f.orientation + 2 * 9, 9), 3e-5);  // the present one anchors
    // the pelvis missing silences every relative block
    f.mask[0] = 0.0f;
    run(g, f, kZero, &feat);
    for (int e = 12 * n; e < 12 * n + 12 * (n - 1); ++e) EXPECT_EQ(feat[e], 0.0f) << e;
}
