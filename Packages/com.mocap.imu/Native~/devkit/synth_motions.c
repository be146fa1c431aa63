/* Procedural body motions and trajectory files for the synthetic capture generator.
 *
 * Every procedural quantity is a second-order jet (value, d/dt, d2/dt2) of time, so the sensor
 * positions of the crude kinematic chain below are differentiated exactly: accelerations are
 * the true second derivative of the positions, and angular velocity comes from dR/dt R^T with
 * no step size to tune. Motions are built from a small set of body parameters (root position,
 * pelvis angles, leg and arm angles, head angles, the chest's twist and bend); blending parameters with C2 weights keeps
 * every transition smooth in position, velocity and acceleration. */
#include "synth.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "platform.h"
#include "mocap_math.h"
#include "text_number.h"

/* ------------------------------------------------------------------------------------------ */
/* Second-order jets                                                                           */
/* ------------------------------------------------------------------------------------------ */
typedef struct jet { double v, d, a; } jet; /* value, first and second time derivative */

static jet jc(double c) { jet r = {c, 0.0, 0.0}; return r; }
static jet jtime(double t) { jet r = {t, 1.0, 0.0}; return r; }
static jet jadd(jet x, jet y) { jet r = {x.v + y.v, x.d + y.d, x.a + y.a}; return r; }
static jet jsub(jet x, jet y) { jet r = {x.v - y.v, x.d - y.d, x.a - y.a}; return r; }
static jet jscale(jet x, double k) { jet r = {x.v * k, x.d * k, x.a * k}; return r; }
static jet jaddc(jet x, double c) { x.v += c; return x; }

static jet jmul(jet x, jet y)
{
    jet r = {x.v * y.v, x.d * y.v + x.v * y.d, x.a * y.v + 2.0 * x.d * y.d + x.v * y.a};
    return r;
}

static jet jsin(jet x)
{
    double s = sin(x.v), c = cos(x.v);
    jet r = {s, c * x.d, c * x.a - s * x.d * x.d};
    return r;
}

static jet jcos(jet x)
{
    double s = sin(x.v), c = cos(x.v);
    jet r = {c, -s * x.d, -s * x.a - c * x.d * x.d};
    return r;
}

/* amp_deg * sin(2 pi f t + phase) in radians. */
static jet jwave_deg(double t, double amp_deg, double freq_hz, double phase)
{
    jet arg = jaddc(jscale(jtime(t), 2.0 * MOCAP_PI * freq_hz), phase);
    return jscale(jsin(arg), amp_deg * MOCAP_DEG2RAD);
}

static jet jdeg(double deg) { return jc(deg * MOCAP_DEG2RAD); }

/* 6u^5 - 15u^4 + 10u^3 of u = (t - t0) / len, clamped: its first and second derivatives vanish
 * at both ends, so anything blended with it stays C2. */
static jet jsmoother(double t, double t0, double len)
{
    double u = (t - t0) / len;
    if (u <= 0.0) return jc(0.0);
    if (u >= 1.0) return jc(1.0);
    jet x = {u, 1.0 / len, 0.0};
    jet x2 = jmul(x, x), x3 = jmul(x2, x);
    jet inner = jadd(jsub(jc(10.0), jscale(x, 15.0)), jscale(x2, 6.0));
    return jmul(x3, inner);
}

/* ((1 - cos 2 pi u) / 2)^2 on u in [0,1], else 0: a C2 bump from 0 up to 1 and back. */
static jet jbump(double t, double t0, double len)
{
    double u = (t - t0) / len;
    if (u <= 0.0 || u >= 1.0) return jc(0.0);
    jet x = {u, 1.0 / len, 0.0};
    jet h = jscale(jsub(jc(1.0), jcos(jscale(x, 2.0 * MOCAP_PI))), 0.5);
    return jmul(h, h);
}

/* Rotation matrices of jets, row-major. */
typedef struct jmat { jet m[9]; } jmat;

static jmat jmat_axis(int axis, jet angle)
{
    jmat r;
    jet c = jcos(angle), s = jsin(angle), z = jc(0.0), o = jc(1.0), ns = jscale(s, -1.0);
    switch (axis) {
    case 0: { jmat x = {{o, z, z, z, c, ns, z, s, c}}; r = x; break; }
    case 1: { jmat y = {{c, z, s, z, o, z, ns, z, c}}; r = y; break; }
    default: { jmat w = {{c, ns, z, s, c, z, z, z, o}}; r = w; break; }
    }
    return r;
}

static jmat jmat_mul(const jmat *a, const jmat *b)
{
    jmat r;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            jet acc = jc(0.0);
            for (int k = 0; k < 3; k++) acc = jadd(acc, jmul(a->m[3 * i + k], b->m[3 * k + j]));
            r.m[3 * i + j] = acc;
        }
    return r;
}

/* out = base + R v (v constant in the rotated frame). */
static void jmat_place(jet out[3], const jet base[3], const jmat *r, double x, double y, double z)
{
    for (int i = 0; i < 3; i++) {
        jet acc = base[i];
        acc = jadd(acc, jscale(r->m[3 * i + 0], x));
        acc = jadd(acc, jscale(r->m[3 * i + 1], y));
        acc = jadd(acc, jscale(r->m[3 * i + 2], z));
        out[i] = acc;
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Body parameters and the kinematic chain                                                     */
/* ------------------------------------------------------------------------------------------ */
/* Angles in radians. Leg angles rotate about model X in the pelvis yaw frame: positive swings
 * the lower end backwards (-Z), so a leg stepping forward has a negative thigh angle. Arm
 * elevation lowers the arm from the T-pose (80 deg = arm hanging); swing then rotates the
 * lowered arm about X (negative = forwards); twist rolls the wrist about the arm's long axis. */
enum {
    P_ROOT_X, P_ROOT_Y, P_ROOT_Z, /* hip-joint centre, model frame, m */
    P_YAW, P_PITCH, P_ROLL,       /* pelvis: yaw about Y, then forward lean about X, roll Z */
    P_THIGH_L, P_THIGH_R, P_SHIN_L, P_SHIN_R,
    P_ELEV_L, P_ELEV_R, P_SWING_L, P_SWING_R, P_TWIST_L, P_TWIST_R,
    P_HEAD_YAW, P_HEAD_PITCH,
    P_CHEST_TWIST, P_CHEST_BEND,  /* upper trunk on the lumbar spine: about Y, then forward */
    P_COUNT
};
typedef struct body { jet p[P_COUNT]; } body;

/* Crude layout (m): hip centre 0.92 above the floor with straight legs. */
#define THIGH_LEN 0.45
#define SHIN_LEN 0.43
#define ANKLE_HEIGHT 0.04
#define ROOT_HEIGHT (ANKLE_HEIGHT + SHIN_LEN + THIGH_LEN)
#define HIP_HALF_WIDTH 0.09
#define SHOULDER_HALF_WIDTH 0.18
#define SHOULDER_HEIGHT 0.48  /* above the hip centre */
#define NECK_HEIGHT 0.56
#define ARM_LEN 0.55          /* shoulder to wrist sensor */
#define LUMBAR_HEIGHT 0.20    /* the joint the chest turns about, above the hip centre */
#define FADE_S 1.0            /* cross-fade between motions */

static void body_rest(body *b)
{
    for (int i = 0; i < P_COUNT; i++) b->p[i] = jc(0.0);
    b->p[P_ROOT_Y] = jc(ROOT_HEIGHT);
}

static void fill_bone(synth_pose *out, int seg, const jmat *r, const jet pos[3])
{
    double m[9], md[9], w[9];
    for (int i = 0; i < 9; i++) { m[i] = r->m[i].v; md[i] = r->m[i].d; }
    double q[4];
    mat3_to_quat(q, m);
    if (q[0] < 0.0) for (int i = 0; i < 4; i++) q[i] = -q[i];
    for (int i = 0; i < 4; i++) out->bone_quat[seg][i] = q[i];
    out->segment_mask |= 1u << seg;
    /* dR/dt R^T is the skew matrix of the model-frame angular velocity. */
    mat3_multiply_transposed(w, md, m);
    out->angular_velocity[seg][0] = 0.5 * (w[7] - w[5]);
    out->angular_velocity[seg][1] = 0.5 * (w[2] - w[6]);
    out->angular_velocity[seg][2] = 0.5 * (w[3] - w[1]);
    for (int i = 0; i < 3; i++) out->accel[seg][i] = pos[i].a;
}

static void body_pose(const body *b, synth_pose *out)
{
    const jet *p = b->p;
    jet root[3] = {p[P_ROOT_X], p[P_ROOT_Y], p[P_ROOT_Z]};
    jmat yaw = jmat_axis(1, p[P_YAW]);
    jmat pitch = jmat_axis(0, p[P_PITCH]);
    jmat roll = jmat_axis(2, p[P_ROLL]);
    jmat tmp = jmat_mul(&yaw, &pitch);
    jmat pelvis = jmat_mul(&tmp, &roll);
    jet pos[3];
    out->segment_mask = 0;

    jmat_place(pos, root, &pelvis, 0.0, 0.08, -0.12); /* on the sacrum */
    fill_bone(out, MOCAP_SEGMENT_PELVIS, &pelvis, pos);

    /* The chest turns on the lumbar spine. The rest of the crude chain (shoulders, neck) stays
     * on the pelvis frame, so adding the chest changes no other segment's motion. */
    jet lumbar[3];
    jmat_place(lumbar, root, &pelvis, 0.0, LUMBAR_HEIGHT, 0.0);
    jmat ct = jmat_axis(1, p[P_CHEST_TWIST]), cb = jmat_axis(0, p[P_CHEST_BEND]);
    tmp = jmat_mul(&pelvis, &ct);
    jmat chest = jmat_mul(&tmp, &cb);
    jmat_place(pos, lumbar, &chest, 0.0, 0.24, 0.11); /* on the sternum */
    fill_bone(out, MOCAP_SEGMENT_CHEST, &chest, pos);

    jet neck[3];
    jmat_place(neck, root, &pelvis, 0.0, NECK_HEIGHT, 0.0);
    jmat hy = jmat_axis(1, p[P_HEAD_YAW]), hp = jmat_axis(0, p[P_HEAD_PITCH]);
    tmp = jmat_mul(&pelvis, &hy);
    jmat head = jmat_mul(&tmp, &hp);
    jmat_place(pos, neck, &head, 0.0, 0.14, 0.02);
    fill_bone(out, MOCAP_SEGMENT_HEAD, &head, pos);

    for (int side = 0; side < 2; side++) {
        double sign = side == 0 ? 1.0 : -1.0; /* left arm along +X, right along -X */
        jet shoulder[3];
        jmat_place(shoulder, root, &pelvis, sign * SHOULDER_HALF_WIDTH, SHOULDER_HEIGHT, 0.0);
        jmat sw = jmat_axis(0, p[P_SWING_L + side]);
        jmat el = jmat_axis(2, jscale(p[P_ELEV_L + side], -sign));
        jmat tw = jmat_axis(0, jscale(p[P_TWIST_L + side], sign));
        jmat a1 = jmat_mul(&pelvis, &sw);
        jmat a2 = jmat_mul(&a1, &el);
        jmat arm = jmat_mul(&a2, &tw);
        jmat_place(pos, shoulder, &arm, sign * ARM_LEN, 0.0, 0.0);
        fill_bone(out, side == 0 ? MOCAP_SEGMENT_LEFT_WRIST : MOCAP_SEGMENT_RIGHT_WRIST, &arm,
                  pos);

        /* Legs hang in the yaw frame so a forward lean of the pelvis does not swing them. */
        jet hip[3], knee[3];
        jmat_place(hip, root, &pelvis, sign * HIP_HALF_WIDTH, 0.0, 0.0);
        jmat th = jmat_axis(0, p[P_THIGH_L + side]), sh = jmat_axis(0, p[P_SHIN_L + side]);
        jmat thigh = jmat_mul(&yaw, &th);
        jmat shin = jmat_mul(&yaw, &sh);
        jmat_place(knee, hip, &thigh, 0.0, -THIGH_LEN, 0.0);
        jmat_place(pos, knee, &shin, 0.0, -0.15, 0.05); /* front of the shin */
        fill_bone(out, side == 0 ? MOCAP_SEGMENT_LEFT_SHIN : MOCAP_SEGMENT_RIGHT_SHIN, &shin, pos);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Raw motions (each in its own frame: root starts near x = z = 0, facing +Z)                  */
/* ------------------------------------------------------------------------------------------ */
#define WALK_STRIDE_HZ 0.9  /* one left + one right step per cycle */
#define WALK_SPEED 1.2

static void raw_tpose(double t, body *b) { (void)t; body_rest(b); }

static void raw_walk(double t, body *b)
{
    body_rest(b);
    jet *p = b->p;
    double f = WALK_STRIDE_HZ;
    jet phi = jscale(jtime(t), 2.0 * MOCAP_PI * f);
    p[P_ROOT_X] = jscale(jsin(phi), 0.03);
    p[P_ROOT_Y] = jadd(jc(ROOT_HEIGHT - 0.02), jscale(jcos(jscale(phi, 2.0)), 0.02));
    p[P_ROOT_Z] = jscale(jtime(t), WALK_SPEED);
    p[P_YAW] = jwave_deg(t, 6.0, f, 0.0);
    p[P_PITCH] = jadd(jdeg(3.0), jwave_deg(t, 1.0, 2.0 * f, 0.5 * MOCAP_PI));
    p[P_ROLL] = jwave_deg(t, 3.0, f, 0.0);
    for (int side = 0; side < 2; side++) {
        jet ph = jaddc(phi, side * MOCAP_PI);
        p[P_THIGH_L + side] = jscale(jsin(ph), -22.0 * MOCAP_DEG2RAD);
        /* Knee flexion peaks while the leg swings forward. */
        jet k = jscale(jaddc(jcos(ph), 1.0), 0.5);
        jet knee = jadd(jdeg(5.0), jscale(jmul(k, k), 55.0 * MOCAP_DEG2RAD));
        p[P_SHIN_L + side] = jadd(p[P_THIGH_L + side], knee);
        p[P_ELEV_L + side] = jdeg(80.0);
        /* Arms swing against the legs: left arm back while the left leg is forward. */
        p[P_SWING_L + side] = jscale(jsin(ph), 18.0 * MOCAP_DEG2RAD);
        p[P_TWIST_L + side] = jwave_deg(t, 5.0, f, side * MOCAP_PI + 0.3);
    }
    p[P_HEAD_YAW] = jwave_deg(t, -5.0, f, 0.0);
    p[P_HEAD_PITCH] = jwave_deg(t, 2.0, 2.0 * f, 0.0);
    /* The thorax counter-rotates against the pelvis and nods with each step. */
    p[P_CHEST_TWIST] = jwave_deg(t, -9.0, f, 0.0);
    p[P_CHEST_BEND] = jwave_deg(t, 2.0, 2.0 * f, 0.3);
}

static void raw_arms(double t, body *b)
{
    body_rest(b);
    jet *p = b->p;
    /* Lateral raises (80 deg = hanging, -70 deg = overhead), then cross-fade into circles. */
    jet w = jsmoother(t, 4.0, 1.0);
    double th = 2.0 * MOCAP_PI / 1.6;
    jet circ = jscale(jtime(t - 4.0), th);
    for (int side = 0; side < 2; side++) {
        jet raise = jadd(jdeg(5.0), jscale(jcos(jscale(jtime(t), 2.0 * MOCAP_PI / 2.5)),
                                            75.0 * MOCAP_DEG2RAD));
        jet elev_c = jadd(jdeg(45.0), jscale(jcos(circ), 35.0 * MOCAP_DEG2RAD));
        jet swing_c = jscale(jsin(circ), -35.0 * MOCAP_DEG2RAD);
        jet twist_c = jscale(jsin(circ), 15.0 * MOCAP_DEG2RAD);
        p[P_ELEV_L + side] = jadd(raise, jmul(w, jsub(elev_c, raise)));
        p[P_SWING_L + side] = jmul(w, swing_c);
        p[P_TWIST_L + side] = jmul(w, twist_c);
    }
    p[P_ROOT_Y] = jadd(jc(ROOT_HEIGHT), jscale(jsin(jscale(jtime(t), 2.0 * MOCAP_PI / 2.5)), 0.005));
    p[P_ROLL] = jwave_deg(t, 2.0, 0.4, 0.0);
    p[P_HEAD_YAW] = jwave_deg(t, 25.0, 0.25, 0.0);
    p[P_HEAD_PITCH] = jwave_deg(t, 8.0, 1.0 / 3.0, 0.0);
    /* The chest follows the gaze a little and arches back as the arms go up. */
    p[P_CHEST_TWIST] = jwave_deg(t, 10.0, 0.25, 0.0);
    p[P_CHEST_BEND] = jscale(jsub(jcos(jscale(jtime(t), 2.0 * MOCAP_PI / 2.5)), jc(1.0)),
                             3.0 * MOCAP_DEG2RAD);
}

static void raw_squat(double t, body *b)
{
    body_rest(b);
    jet *p = b->p;
    /* s: 0 standing, 1 deepest; the hip height and depth follow from the leg angles so the
     * ankles stay where they are. */
    jet s = jscale(jsub(jc(1.0), jcos(jscale(jtime(t), 2.0 * MOCAP_PI / 2.5))), 0.5);
    jet thigh = jscale(s, -75.0 * MOCAP_DEG2RAD);
    jet shin = jscale(s, 25.0 * MOCAP_DEG2RAD);
    for (int side = 0; side < 2; side++) {
        p[P_THIGH_L + side] = thigh;
        p[P_SHIN_L + side] = shin;
        p[P_ELEV_L + side] = jdeg(80.0);
        p[P_SWING_L + side] = jscale(s, -80.0 * MOCAP_DEG2RAD); /* arms forward for balance */
    }
    p[P_ROOT_Y] = jadd(jc(ANKLE_HEIGHT), jadd(jscale(jcos(thigh), THIGH_LEN),
                                              jscale(jcos(shin), SHIN_LEN)));
    p[P_ROOT_Z] = jadd(jscale(jsin(thigh), THIGH_LEN), jscale(jsin(shin), SHIN_LEN));
    p[P_PITCH] = jscale(s, 25.0 * MOCAP_DEG2RAD);
    p[P_HEAD_PITCH] = jscale(s, -15.0 * MOCAP_DEG2RAD); /* keep looking ahead */
    p[P_CHEST_BEND] = jscale(s, 12.0 * MOCAP_DEG2RAD);  /* the back rounds a little */
}

#define TURN_START 0.4
#define TURN_LEN 4.2

static void raw_turn(double t, body *b)
{
    body_rest(b);
    jet *p = b->p;
    double f = WALK_STRIDE_HZ;
    jet phi = jscale(jtime(t), 2.0 * MOCAP_PI * f);
    p[P_YAW] = jscale(jsmoother(t, TURN_START, TURN_LEN), 2.0 * MOCAP_PI);
    /* Stepping in place while turning: each leg lifts once per cycle. */
    jet active = jbump(t, 0.0, 5.0);
    for (int side = 0; side < 2; side++) {
        jet c = jscale(jadd(jc(1.0), jscale(jcos(phi), side == 0 ? -1.0 : 1.0)), 0.5);
        jet lift = jmul(active, jmul(c, c));
        p[P_THIGH_L + side] = jscale(lift, -30.0 * MOCAP_DEG2RAD);
        p[P_SHIN_L + side] = jscale(lift, 30.0 * MOCAP_DEG2RAD);
        p[P_ELEV_L + side] = jdeg(75.0);
        p[P_SWING_L + side] = jmul(active, jscale(jsin(jaddc(phi, side * MOCAP_PI)),
                                                  10.0 * MOCAP_DEG2RAD));
    }
    p[P_ROOT_Y] = jsub(jc(ROOT_HEIGHT),
                       jmul(active, jscale(jsub(jc(1.0), jcos(jscale(phi, 2.0))), 0.005)));
    p[P_HEAD_YAW] = jscale(jbump(t, TURN_START, TURN_LEN), 20.0 * MOCAP_DEG2RAD); /* leads */
    p[P_CHEST_TWIST] = jscale(jbump(t, TURN_START, TURN_LEN), 10.0 * MOCAP_DEG2RAD); /* so does the chest */
}

typedef void (*raw_fn)(double t, body *b);
typedef struct motion_item {
    raw_fn fn;
    double duration;
    double net_yaw; /* yaw the item ends with, carried into the next item */
} motion_item;

static const motion_item TPOSE_ITEM = {raw_tpose, FADE_S, 0.0};
static const motion_item WALK_ITEM = {raw_walk, 6.0, 0.0};
static const motion_item ARMS_ITEM = {raw_arms, 8.0, 0.0};
static const motion_item SQUAT_ITEM = {raw_squat, 5.0, 0.0};
static const motion_item TURN_ITEM = {raw_turn, 6.0, 2.0 * MOCAP_PI};

#define MAX_ITEMS 8

/* Evaluate item k at global time t with its offsets (yaw, and root x/z). */
static void item_eval(const motion_item *item, double start, const double off[3], double t,
                      body *b)
{
    item->fn(t - start, b);
    double c = cos(off[2]), s = sin(off[2]);
    jet x = b->p[P_ROOT_X], z = b->p[P_ROOT_Z];
    b->p[P_ROOT_X] = jaddc(jadd(jscale(x, c), jscale(z, s)), off[0]);
    b->p[P_ROOT_Z] = jaddc(jsub(jscale(z, c), jscale(x, s)), off[1]);
    b->p[P_YAW] = jaddc(b->p[P_YAW], off[2]);
}

/* A sequence of items, each cross-fading into the next over FADE_S; every item after the first
 * continues from where the previous one stood at the middle of their cross-fade. Returns -1
 * past the end; t < 0 gives the first pose. */
static int sequence_eval(const motion_item *const *items, int count, double t, synth_pose *out)
{
    double start[MAX_ITEMS], off[MAX_ITEMS][3];
    double total = 0.0;
    body b, nb;
    start[0] = 0.0;
    off[0][0] = off[0][1] = off[0][2] = 0.0;
    for (int k = 1; k < count; k++) {
        start[k] = start[k - 1] + items[k - 1]->duration - FADE_S;
        item_eval(items[k - 1], start[k - 1], off[k - 1], start[k] + 0.5 * FADE_S, &b);
        off[k][0] = b.p[P_ROOT_X].v;
        off[k][1] = b.p[P_ROOT_Z].v;
        off[k][2] = off[k - 1][2] + items[k - 1]->net_yaw;
    }
    total = start[count - 1] + items[count - 1]->duration;
    if (!(t <= total)) return -1;
    if (t < 0.0) t = 0.0;
    int k = 0;
    while (k + 1 < count && t >= start[k] + items[k]->duration) k++;
    item_eval(items[k], start[k], off[k], t, &b);
    if (k + 1 < count && t >= start[k + 1]) {
        jet w = jsmoother(t, start[k + 1], FADE_S);
        item_eval(items[k + 1], start[k + 1], off[k + 1], t, &nb);
        for (int i = 0; i < P_COUNT; i++)
            b.p[i] = jadd(b.p[i], jmul(w, jsub(nb.p[i], b.p[i])));
    }
    body_pose(&b, out);
    return 0;
}

#define SEQUENCE_MOTION(name, ...)                                                       \
    static int name(void *user, double t, synth_pose *out)                                \
    {                                                                                    \
        static const motion_item *const items[] = {__VA_ARGS__};                         \
        (void)user;                                                                      \
        return sequence_eval(items, (int)(sizeof items / sizeof items[0]), t, out);      \
    }

SEQUENCE_MOTION(motion_walk, &TPOSE_ITEM, &WALK_ITEM, &TPOSE_ITEM)
SEQUENCE_MOTION(motion_arms, &TPOSE_ITEM, &ARMS_ITEM, &TPOSE_ITEM)
SEQUENCE_MOTION(motion_squat, &TPOSE_ITEM, &SQUAT_ITEM, &TPOSE_ITEM)
SEQUENCE_MOTION(motion_turn, &TPOSE_ITEM, &TURN_ITEM, &TPOSE_ITEM)
SEQUENCE_MOTION(motion_mixed, &TPOSE_ITEM, &WALK_ITEM, &ARMS_ITEM, &SQUAT_ITEM, &TURN_ITEM,
                &TPOSE_ITEM)

synth_motion_fn synth_builtin_motion(const char *name)
{
    if (!name || !name[0] || strcmp(name, "mixed") == 0) return motion_mixed;
    if (strcmp(name, "walk") == 0) return motion_walk;
    if (strcmp(name, "arms") == 0) return motion_arms;
    if (strcmp(name, "squat") == 0) return motion_squat;
    if (strcmp(name, "turn") == 0) return motion_turn;
    return NULL;
}

/* ------------------------------------------------------------------------------------------ */
/* Trajectory files                                                                            */
/* ------------------------------------------------------------------------------------------ */
#define TRAJ_MAX_VALUES (1 + MOCAP_MAX_SENSORS * 7)

/* Column group k of a line belongs to the file's segment k. */
typedef struct traj_frame {
    double t;
    double q[MOCAP_MAX_SENSORS][4];
    double a[MOCAP_MAX_SENSORS][3];
    double w[MOCAP_MAX_SENSORS][3]; /* angular velocity estimated at load */
} traj_frame;

struct synth_trajectory {
    size_t count;
    int segment_count;
    int32_t segments[MOCAP_MAX_SENSORS];
    traj_frame frames[]; /* one allocation with the header */
};

/* Rotation vector of a unit quaternion (angle * axis), taking the short way round. */
static void quat_rotvec(double out[3], const double q[4])
{
    double w = q[0], v[3] = {q[1], q[2], q[3]};
    if (w < 0.0) { w = -w; v[0] = -v[0]; v[1] = -v[1]; v[2] = -v[2]; }
    double s = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    double k = s < 1e-12 ? 2.0 : 2.0 * atan2(s, w) / s;
    for (int i = 0; i < 3; i++) out[i] = v[i] * k;
}

/* Model-frame angular velocity taking orientation a at ta to b at tb. */
static void angular_velocity_between(double out[3], const double a[4], const double b[4],
                                     double dt)
{
    double ac[4], d[4];
    quat_conjugate(ac, a);
    quat_multiply(d, b, ac);
    quat_rotvec(out, d);
    for (int i = 0; i < 3; i++) out[i] /= dt;
}

static mocap_status read_whole_file(const char *path, char **text, size_t *len)
{
    FILE *f = mocap_fopen(path, "rb");
    if (!f) {
        int e = errno;
        char buf[128];
        mocap_status st = e == ENOENT ? MOCAP_ERR_NOT_FOUND
                          : (e == EACCES || e == EPERM) ? MOCAP_ERR_PERMISSION : MOCAP_ERR_IO;
        return mocap_fail(st, "trajectory file %s: %s", path, mocap_errno_text(e, buf, sizeof buf));
    }
    size_t cap = 1 << 16, n = 0;
    char *data = malloc(cap);
    if (!data) { fclose(f); return mocap_fail(MOCAP_ERR_NO_MEMORY, "trajectory file %s: out of memory", path); }
    for (;;) {
        if (cap - n < 2) {
            char *grown = realloc(data, cap * 2);
            if (!grown) {
                free(data);
                fclose(f);
                return mocap_fail(MOCAP_ERR_NO_MEMORY, "trajectory file %s: out of memory", path);
            }
            data = grown;
            cap *= 2;
        }
        size_t got = fread(data + n, 1, cap - n - 1, f);
        n += got;
        if (got == 0) break;
    }
    int failed = ferror(f);
    fclose(f);
    if (failed) {
        free(data);
        return mocap_fail(MOCAP_ERR_IO, "trajectory file %s: read error", path);
    }
    data[n] = '\0';
    *text = data;
    *len = n;
    return MOCAP_OK;
}

/* Parses one line (already cut at '#' and NUL-terminated) of at most `limit` values. Returns the
 * number of values read, or -1 when a token is not a finite number, limit + 1 when there are
 * too many. */
static int parse_line(char *line, double *v, int limit, char **bad)
{
    int n = 0;
    char *p = line;
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == ',') p++;
        if (!*p) return n;
        if (n == limit) return limit + 1;
        char *end = NULL;
        double x = text_strtod(p, &end);
        if (end == p || !isfinite(x) ||
            (*end && *end != ' ' && *end != '\t' && *end != '\r' && *end != ',')) {
            *bad = p;
            return -1;
        }
        v[n++] = x;
        p = end;
    }
}

/* 1 when the line's first word is "segments" (the header naming the file's segments). */
static int is_segments_line(const char *line)
{
    while (*line == ' ' || *line == '\t') line++;
    return strncmp(line, "segments", 8) == 0 &&
           (line[8] == '\0' || line[8] == ' ' || line[8] == '\t' || line[8] == '\r');
}

/* "segments NAME NAME ...": the segment of each column group, by the names of the engine's
 * table, each at most once. */
static mocap_status parse_segments_line(char *line, int32_t segments[MOCAP_MAX_SENSORS],
                                        int *count, const char *path, unsigned long line_no)
{
    char *p = strstr(line, "segments") + 8;
    int n = 0;
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == ',') p++;
        if (!*p) break;
        char *end = p;
        while (*end && *end != ' ' && *end != '\t' && *end != '\r' && *end != ',') end++;
        const char saved = *end;
        *end = '\0';
        const int32_t seg = mocap_segment_find(p);
        if (seg < 0)
            return mocap_fail(MOCAP_ERR_FORMAT, "trajectory file %s line %lu: unknown segment '%s'",
                              path, line_no, p);
        for (int k = 0; k < n; k++)
            if (segments[k] == seg)
                return mocap_fail(MOCAP_ERR_FORMAT,
                                  "trajectory file %s line %lu: segment %s is named twice", path,
                                  line_no, p);
        if (n == MOCAP_MAX_SENSORS)
            return mocap_fail(MOCAP_ERR_FORMAT, "trajectory file %s line %lu: more than %d segments",
                              path, line_no, MOCAP_MAX_SENSORS);
        segments[n++] = seg;
        *end = saved;
        p = end;
    }
    if (n == 0)
        return mocap_fail(MOCAP_ERR_FORMAT, "trajectory file %s line %lu: the segments line names none",
                          path, line_no);
    *count = n;
    return MOCAP_OK;
}

mocap_status synth_trajectory_load(const char *path, synth_trajectory **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth_trajectory_load: out is NULL");
    *out = NULL;
    if (!path || !path[0])
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth_trajectory_load: empty path");
    char *text = NULL;
    size_t len = 0;
    mocap_status st = read_whole_file(path, &text, &len);
    if (st != MOCAP_OK) return st;

    size_t lines = 1;
    for (size_t i = 0; i < len; i++) lines += text[i] == '\n';
    synth_trajectory *traj = malloc(sizeof *traj + lines * sizeof(traj_frame));
    if (!traj) {
        free(text);
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "trajectory file %s: out of memory", path);
    }
    traj->count = 0;
    /* Without a segments line: the engine's default set, in its order. */
    mocap_session_config defaults;
    mocap_config_defaults(&defaults);
    traj->segment_count = (int)defaults.sensor_count;
    for (int k = 0; k < traj->segment_count; k++) traj->segments[k] = defaults.sensor_segments[k];

    char *line = text;
    unsigned long line_no = 0;
    while (line && st == MOCAP_OK) {
        line_no++;
        char *next = strchr(line, '\n');
        if (next) *next++ = '\0';
        char *hash = strchr(line, '#');
        if (hash) *hash = '\0';
        if (is_segments_line(line)) {
            if (traj->count > 0) {
                st = mocap_fail(MOCAP_ERR_FORMAT,
                                "trajectory file %s line %lu: the segments line must come before "
                                "the first sample", path, line_no);
                break;
            }
            st = parse_segments_line(line, traj->segments, &traj->segment_count, path, line_no);
            line = next;
            continue;
        }
        const int expected = 1 + 7 * traj->segment_count;
        double v[TRAJ_MAX_VALUES];
        char *bad = NULL;
        int n = parse_line(line, v, expected, &bad);
        if (n == 0) { line = next; continue; }
        if (n < 0) {
            char token[24];
            size_t k = 0;
            while (bad[k] && bad[k] != ' ' && bad[k] != '\t' && k + 1 < sizeof token) {
                token[k] = bad[k];
                k++;
            }
            token[k] = '\0';
            st = mocap_fail(MOCAP_ERR_FORMAT, "trajectory file %s line %lu: '%s' is not a finite number",
                            path, line_no, token);
            break;
        }
        if (n != expected) {
            st = mocap_fail(MOCAP_ERR_FORMAT,
                            "trajectory file %s line %lu: expected %d numbers (t, then qw qx qy qz "
                            "ax ay az for %d segments), found %s%d",
                            path, line_no, expected, traj->segment_count,
                            n > expected ? "more than " : "", n > expected ? expected : n);
            break;
        }
        traj_frame *fr = &traj->frames[traj->count];
        fr->t = v[0];
        if (traj->count > 0 && !(fr->t > traj->frames[traj->count - 1].t)) {
            st = mocap_fail(MOCAP_ERR_FORMAT,
                            "trajectory file %s line %lu: time %.9g does not increase (previous %.9g)",
                            path, line_no, fr->t, traj->frames[traj->count - 1].t);
            break;
        }
        for (int s = 0; s < traj->segment_count; s++) {
            const double *g = &v[1 + 7 * s];
            for (int i = 0; i < 4; i++) fr->q[s][i] = g[i];
            for (int i = 0; i < 3; i++) fr->a[s][i] = g[4 + i];
            double norm = quat_norm(fr->q[s]);
            if (!(norm > 0.5 && norm < 1.5)) {
                st = mocap_fail(MOCAP_ERR_FORMAT,
                                "trajectory file %s line %lu: quaternion of segment %s has norm %.6g "
                                "(expected 1)",
                                path, line_no, mocap_segment_name(traj->segments[s]), norm);
                break;
            }
            quat_normalize(fr->q[s]);
            /* Keep consecutive samples in one hemisphere so interpolation and differencing
             * never see a sign flip. */
            if (traj->count > 0)
                quat_align_hemisphere(fr->q[s], traj->frames[traj->count - 1].q[s]);
        }
        if (st != MOCAP_OK) break;
        traj->count++;
        line = next;
    }
    free(text);
    if (st == MOCAP_OK && traj->count == 0)
        st = mocap_fail(MOCAP_ERR_FORMAT, "trajectory file %s: no samples", path);
    if (st != MOCAP_OK) {
        free(traj);
        return st;
    }

    /* Angular velocity at each sample by central differences (one-sided at the ends). */
    for (size_t k = 0; k < traj->count; k++) {
        size_t lo = k > 0 ? k - 1 : k, hi = k + 1 < traj->count ? k + 1 : k;
        for (int s = 0; s < traj->segment_count; s++) {
            if (lo == hi) {
                traj->frames[k].w[s][0] = traj->frames[k].w[s][1] = traj->frames[k].w[s][2] = 0.0;
                continue;
            }
            angular_velocity_between(traj->frames[k].w[s], traj->frames[lo].q[s],
                                     traj->frames[hi].q[s],
                                     traj->frames[hi].t - traj->frames[lo].t);
        }
    }
    *out = traj;
    return MOCAP_OK;
}

double synth_motion_duration(synth_motion_fn motion, void *user, double limit)
{
    synth_pose pose;
    if (!motion || motion(user, 0.0, &pose) != 0) return 0.0;
    if (motion(user, limit, &pose) == 0) return limit;
    /* Motions run from 0 to their end without holes: bisect on "still running". */
    double lo = 0.0, hi = limit;
    while (hi - lo > 1e-3) {
        const double mid = 0.5 * (lo + hi);
        if (motion(user, mid, &pose) == 0) lo = mid;
        else hi = mid;
    }
    return lo;
}

void synth_trajectory_free(synth_trajectory *traj) { free(traj); }

uint32_t synth_trajectory_segment_mask(const synth_trajectory *traj)
{
    uint32_t mask = 0;
    for (int k = 0; traj && k < traj->segment_count; k++) mask |= 1u << traj->segments[k];
    return mask;
}

double synth_trajectory_duration(const synth_trajectory *traj)
{
    if (!traj || traj->count == 0) return 0.0;
    return traj->frames[traj->count - 1].t - traj->frames[0].t;
}

int synth_trajectory_motion(void *user, double t, synth_pose *out)
{
    const synth_trajectory *traj = user;
    if (!traj || !out || traj->count == 0 || isnan(t)) return -1;
    const traj_frame *f = traj->frames;
    /* Motion time 0 is the first sample, whatever time the file starts at. */
    double ft = f[0].t + (t < 0.0 ? 0.0 : t);
    size_t n = traj->count;
    if (ft > f[n - 1].t) return -1;
    size_t lo = 0, hi = n - 1;
    while (hi - lo > 1) { /* f[lo].t <= ft <= f[hi].t */
        size_t mid = lo + (hi - lo) / 2;
        if (f[mid].t <= ft) lo = mid; else hi = mid;
    }
    double u = hi == lo ? 0.0 : (ft - f[lo].t) / (f[hi].t - f[lo].t);
    if (u < 0.0) u = 0.0;
    if (u > 1.0) u = 1.0;
    out->segment_mask = 0;
    for (int s = 0; s < traj->segment_count; s++) {
        const int seg = traj->segments[s];
        if (u == 0.0) quat_copy(out->bone_quat[seg], f[lo].q[s]);
        else if (u == 1.0) quat_copy(out->bone_quat[seg], f[hi].q[s]);
        else quat_slerp(out->bone_quat[seg], f[lo].q[s], f[hi].q[s], u);
        for (int i = 0; i < 3; i++) {
            out->accel[seg][i] = f[lo].a[s][i] + u * (f[hi].a[s][i] - f[lo].a[s][i]);
            out->angular_velocity[seg][i] = f[lo].w[s][i] + u * (f[hi].w[s][i] - f[lo].w[s][i]);
        }
        out->segment_mask |= 1u << seg;
    }
    return 0;
}
