#!/usr/bin/env python3
"""Tiny ONNX models for testing the engine's ONNX Runtime module (and training/ort.py).

    python3 make_onnx_fixtures.py OUTDIR      # writes every variant below into OUTDIR

`valid.onnx` follows docs/model-contract.md (L = 2, H = 4) with outputs that are easy to predict:

    a[b, t]                = sum of imu_acceleration[b, t, :, :]            (scalar per frame)
    c[b]                   = mean of state_in_h[:, b, :]                     (carried total)
    joint_rotations[b, t, j] = imu_orientation[b, t, j % 6]                  (Tile x4)
    root_velocity[b, t, :] = c[b] + cumsum_t a[b, :t+1]                      (causal, stateful)
    foot_contact[b, t, :]  = sigmoid(root_velocity[b, t, 0:2])
    state_out_h            = state_in_h + sum_t a[b, t]                      (broadcast over L, H)
    state_out_c            = 0.5 * state_in_c + 1

so streaming one frame per call and one call for a whole clip give the same results, which the
tests check.

`v2_chest.onnx` follows contract version 2: its own sensor list, the six of `valid` plus the
chest (`mocap.sensor_order` pelvis,left_wrist,right_wrist,left_shin,right_shin,head,chest;
`mocap.sensor_required` 1,1,1,1,1,1,0: the chest is optional), inputs imu_orientation
[B, T, 7, 3, 3], imu_acceleration [B, T, 7, 3], imu_mask [B, T, 7], state [L = 2, B, H = 4]:

    m6                       = imu_mask[b, t, 6]                              (the chest's mask)
    joint_rotations[b, t, 0] = imu_orientation[b, t, 0]
    joint_rotations[b, t, 9] = m6 * imu_orientation[b, t, 6] + (1 - m6) * I    (I: identity 3x3)
    joint_rotations[b, t, j] = I                                               (every other j)
    root_velocity[b, t, :]   = (sum over k of imu_mask[b, t, k], m6, imu_acceleration[b, t, 6, 1])
    foot_contact             = 0
    state_out_h              = state_in_h + 1
    state_out_c              = state_in_c

so a test sees which sensors the engine marked present, that the chest reached joint 9, and what
the engine fed as the chest's acceleration.

`v3_network` follows contract version 3: the learned network alone, the geometry left to the
engine. Six sensors, masked features (F = 6 x 12 + 5 x 12 + 6 = 138), the mirror average (two
rows per character), wrist sensors anchoring the hands; the graph's state is [L = 2, R, 2] (the
metadata's state size 4 holds both rows):

    network_output[r, t, :] = network_input[r, t, :] @ W + bias     (W: 1 from the pelvis'
                              heading-frame acceleration x (feature 54) to the heading-frame root
                              velocity x (output 144), 0 elsewhere; bias: 1 at the velocity z,
                              +2 / -2 at the contact logits, 0 elsewhere)
    state_out_h             = state_in_h + 1
    state_out_c             = state_in_c

so every residual is zero: the engine must answer the rest pose under the measured pelvis with
the present hands turned as their sensors, contact 0.5, and the root velocity Ry (x, 0, 1) with
x = (Ry^T a_pelvis)_x / 30 of that character's frame (both rows of the mirror average agree on
it, so a row or frame fed another's features shows). `v3_missing_anchor_joints` lacks mocap.anchor_joints, `v3_wrong_features` reads the 132
features of an unmasked network while declaring masked ones, `v3_unmasked_optional` makes the
head optional in a network without the mask, `v3_bad_mirror_table` pairs the
left wrist with itself (so the right wrist pairs with the left one way only).

`stride_scaled` is `valid` with the optional stride scaling (`mocap.training_height` 1.70,
`mocap.stride_exponent` 0.6); `stride_height_only` gives the height alone and
`stride_bad_exponent` an exponent of 3, both refused.

The other variants break the contract in one way each; the engine must refuse them with a
message naming the difference. Every variant is checked with onnx.checker (the defects are in
the contract, not in ONNX). Needs only the `onnx` Python package (Debian python3-onnx).
"""
import os
import sys

import numpy as np
from onnx import TensorProto, checker, helper, save

JOINTS = ["pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
          "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar",
          "right_collar", "head", "left_shoulder", "right_shoulder", "left_elbow", "right_elbow",
          "left_wrist", "right_wrist", "left_hand", "right_hand"]
PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
# Made-up rest offsets for fixtures (metres); only their format matters here.
OFFSETS = np.zeros((24, 3), np.float32)
OFFSETS[0] = (0, 0.93, 0)
for j in range(1, 24):
    OFFSETS[j] = (0.05 * ((j % 3) - 1), 0.1 if j in (3, 6, 9, 12, 15) else -0.1, 0.01)
SENSORS = "pelvis,left_wrist,right_wrist,left_shin,right_shin,head"
SENSORS_V2 = SENSORS + ",chest"
REQUIRED_V2 = "1,1,1,1,1,1,0"
CHEST, CHEST_JOINT = 6, 9
LAYERS, SIZE = 2, 4

VARIANTS = ["valid", "wrong_input_name", "wrong_rank", "missing_metadata", "missing_joint_names",
            "wrong_version", "state_mismatch", "fixed_batch", "wrong_joint_name", "symbolic_dims",
            "wrong_output_shape", "rank_nine_output", "fails_on_impact", "v1_with_mask",
            "v2_chest", "v2_unknown_segment", "v2_required_length", "v2_missing_mask",
            "v2_wrong_sensor_dim", "v2_duplicate_segment", "int8_precision", "unknown_precision",
            "stride_scaled", "stride_height_only", "stride_bad_exponent", "v3_network",
            "v3_missing_anchor_joints", "v3_wrong_features", "v3_bad_mirror_table",
            "v3_unmasked_optional"]
MIRROR_JOINTS = [0, 2, 1, 3, 5, 4, 6, 8, 7, 9, 11, 10, 12, 14, 13, 15, 17, 16, 19, 18, 21, 20, 23, 22]


def metadata(**override):
    md = {
        "mocap.contract_version": "1",
        "mocap.frame_rate": "60",
        "mocap.sensor_order": SENSORS,
        "mocap.joint_names": ",".join(JOINTS),
        "mocap.joint_parents": ",".join(str(p) for p in PARENTS),
        "mocap.rest_offsets": ",".join(f"{v:.4f}" for v in OFFSETS.reshape(-1)),
        "mocap.state_layers": str(LAYERS),
        "mocap.state_size": str(SIZE),
        "mocap.precision": "fp32",
        "mocap.model_name": "fixture",
    }
    for k, v in override.items():
        key = "mocap." + k
        if v is None:
            md.pop(key, None)
        else:
            md[key] = v
    return md


def _const(name, values, dtype=np.int64):
    arr = np.asarray(values, dtype=dtype)
    return helper.make_tensor(name, TensorProto.INT64 if dtype == np.int64 else TensorProto.FLOAT,
                              arr.shape, arr.reshape(-1).tolist())


def _outputs(B):
    return [
        helper.make_tensor_value_info("joint_rotations", TensorProto.FLOAT, [B, "T", 24, 3, 3]),
        helper.make_tensor_value_info("root_velocity", TensorProto.FLOAT, [B, "T", 3]),
        helper.make_tensor_value_info("foot_contact", TensorProto.FLOAT, [B, "T", 2]),
        helper.make_tensor_value_info("state_out_h", TensorProto.FLOAT, [LAYERS, B, SIZE]),
        helper.make_tensor_value_info("state_out_c", TensorProto.FLOAT, [LAYERS, B, SIZE]),
    ]


def _model(nodes, inputs, outputs, inits, md):
    graph = helper.make_graph(nodes, "mocap_fixture", inputs, outputs, inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)],
                              producer_name="make_onnx_fixtures")
    model.ir_version = 7
    helper.set_model_props(model, md)
    return model


def build_v2(variant="v2_chest"):
    """The ModelProto of a contract-2 variant (formulas in the module docstring)."""
    n = 7
    B = "B"
    ori_sensors = 6 if variant == "v2_wrong_sensor_dim" else n
    inputs = [
        helper.make_tensor_value_info("imu_orientation", TensorProto.FLOAT, [B, "T", ori_sensors, 3, 3]),
        helper.make_tensor_value_info("imu_acceleration", TensorProto.FLOAT, [B, "T", n, 3]),
        helper.make_tensor_value_info("imu_mask", TensorProto.FLOAT, [B, "T", n]),
        helper.make_tensor_value_info("state_in_h", TensorProto.FLOAT, [LAYERS, B, SIZE]),
        helper.make_tensor_value_info("state_in_c", TensorProto.FLOAT, [LAYERS, B, SIZE]),
    ]
    inits = [
        _const("first", [0]), _const("after_first", [1]),
        _const("chest", [CHEST]), _const("after_chest", [CHEST + 1]),
        _const("axis2", [2]), _const("axis3", [3]), _const("axes34", [3, 4]),
        _const("acc_start", [CHEST, 1]), _const("acc_end", [CHEST + 1, 2]), _const("axes23", [2, 3]),
        _const("eye", np.eye(3, dtype=np.float32).reshape(1, 1, 1, 3, 3), np.float32),
        _const("one", np.float32(1.0), np.float32),
        _const("zero", np.float32(0.0), np.float32),
        _const("zeros2", np.zeros(2, np.float32), np.float32),
        _const("before_chest", [1, 1, CHEST_JOINT - 1, 1, 1]),
        _const("after_chest_joints", [1, 1, 24 - CHEST_JOINT - 1, 1, 1]),
    ]
    nodes = []
    if variant == "v2_missing_mask":
        # No mask input: the graph makes its own (all ones) from the accelerations' shape.
        inputs = [i for i in inputs if i.name != "imu_mask"]
        nodes += [
            helper.make_node("Slice", ["imu_acceleration", "first", "after_first", "axis3"], ["acc_x"]),
            helper.make_node("Squeeze", ["acc_x", "axis3"], ["acc_x3"]),                   # [B,T,7]
            helper.make_node("Mul", ["acc_x3", "zero"], ["acc_zero"]),
            helper.make_node("Add", ["acc_zero", "one"], ["imu_mask"]),
        ]
    nodes += [
        # the chest's mask, [B,T,1] and as [B,T,1,1,1] to scale its rotation
        helper.make_node("Slice", ["imu_mask", "chest", "after_chest", "axis2"], ["m6"]),
        helper.make_node("Unsqueeze", ["m6", "axes34"], ["m6_5"]),
        helper.make_node("Sub", ["one", "m6_5"], ["not_m6_5"]),
        # joint 0 = sensor 0; joint 9 = the chest where present, else identity
        helper.make_node("Slice", ["imu_orientation", "first", "after_first", "axis2"], ["ori0"]),
        helper.make_node("Slice", ["imu_orientation", "chest", "after_chest", "axis2"], ["ori6"]),
        helper.make_node("Mul", ["m6_5", "ori6"], ["chest_seen"]),
        helper.make_node("Mul", ["not_m6_5", "eye"], ["chest_rest"]),
        helper.make_node("Add", ["chest_seen", "chest_rest"], ["joint9"]),
        # identities [B,T,k,3,3] for the joints in between and after
        helper.make_node("Shape", ["ori0"], ["one_joint_shape"]),
        helper.make_node("Expand", ["eye", "one_joint_shape"], ["eye1"]),
        helper.make_node("Tile", ["eye1", "before_chest"], ["rest_before"]),
        helper.make_node("Tile", ["eye1", "after_chest_joints"], ["rest_after"]),
        helper.make_node("Concat", ["ori0", "rest_before", "joint9", "rest_after"], ["joint_rotations"], axis=2),
        # root_velocity = (sum of the mask, the chest's mask, chest acceleration y)
        helper.make_node("ReduceSum", ["imu_mask", "axis2"], ["mask_sum"], keepdims=1),      # [B,T,1]
        helper.make_node("Slice", ["imu_acceleration", "acc_start", "acc_end", "axes23"], ["acc6y"]),
        helper.make_node("Squeeze", ["acc6y", "axis3"], ["acc6y3"]),                       # [B,T,1]
        helper.make_node("Concat", ["mask_sum", "m6", "acc6y3"], ["root_velocity"], axis=2),
        helper.make_node("Shape", ["mask_sum"], ["frame_shape"]),
        helper.make_node("Expand", ["zeros2", "frame_shape"], ["foot_contact"]),           # [B,T,2]
        helper.make_node("Add", ["state_in_h", "one"], ["state_out_h"]),
        helper.make_node("Identity", ["state_in_c"], ["state_out_c"]),
    ]
    sensors = {"v2_unknown_segment": SENSORS + ",tail",
               "v2_duplicate_segment": SENSORS + ",head"}.get(variant, SENSORS_V2)
    required = "1,1,1,1,1,1" if variant == "v2_required_length" else REQUIRED_V2
    md = metadata(contract_version="2", sensor_order=sensors, sensor_required=required)
    return _model(nodes, inputs, _outputs(B), inits, md)


def build_v3(variant="v3_network"):
    """The ModelProto of a contract-3 variant (formulas in the module docstring)."""
    features = 132 if variant == "v3_wrong_features" else 138
    half = SIZE // 2
    inputs = [
        helper.make_tensor_value_info("network_input", TensorProto.FLOAT, ["R", "T", features]),
        helper.make_tensor_value_info("state_in_h", TensorProto.FLOAT, [LAYERS, "R", half]),
        helper.make_tensor_value_info("state_in_c", TensorProto.FLOAT, [LAYERS, "R", half]),
    ]
    outputs = [
        helper.make_tensor_value_info("network_output", TensorProto.FLOAT, ["R", "T", 149]),
        helper.make_tensor_value_info("state_out_h", TensorProto.FLOAT, [LAYERS, "R", half]),
        helper.make_tensor_value_info("state_out_c", TensorProto.FLOAT, [LAYERS, "R", half]),
    ]
    bias = np.zeros(149, np.float32)
    bias[146], bias[147], bias[148] = 1.0, 2.0, -2.0
    weights = np.zeros((features, 149), np.float32)
    weights[54, 144] = 1.0
    inits = [_const("weights", weights, np.float32),
             _const("bias", bias, np.float32), _const("one", np.float32(1.0), np.float32)]
    nodes = [
        helper.make_node("MatMul", ["network_input", "weights"], ["product"]),
        helper.make_node("Add", ["product", "bias"], ["network_output"]),
        helper.make_node("Add", ["state_in_h", "one"], ["state_out_h"]),
        helper.make_node("Identity", ["state_in_c"], ["state_out_c"]),
    ]
    md = metadata(contract_version="3", acceleration_scale="30", anchor_joints="0,22,23,4,5,15",
                  masked_features="1", mirror_average="1", mirror_sensors="0,2,1,4,3,5",
                  mirror_joints=",".join(str(j) for j in MIRROR_JOINTS))
    if variant == "v3_missing_anchor_joints":
        md.pop("mocap.anchor_joints")
    if variant == "v3_unmasked_optional":
        md["mocap.masked_features"] = "0"
        md["mocap.sensor_required"] = "1,1,1,1,1,0"
    if variant == "v3_bad_mirror_table":
        md["mocap.mirror_sensors"] = "0,1,1,4,3,5"
    return _model(nodes, inputs, outputs, inits, md)


def build(variant="valid"):
    """The ModelProto of one variant."""
    if variant.startswith("v2_"):
        return build_v2(variant)
    if variant.startswith("v3_"):
        return build_v3(variant)
    ori_name = "imu_orient" if variant == "wrong_input_name" else "imu_orientation"
    B = 1 if variant == "fixed_batch" else "B"
    ori_shape = [B, "T", 54] if variant == "wrong_rank" else [B, "T", 6, 3, 3]
    inputs = [
        helper.make_tensor_value_info(ori_name, TensorProto.FLOAT, ori_shape),
        helper.make_tensor_value_info("imu_acceleration", TensorProto.FLOAT, [B, "T", 6, 3]),
        helper.make_tensor_value_info("state_in_h", TensorProto.FLOAT, [LAYERS, B, SIZE]),
        helper.make_tensor_value_info("state_in_c", TensorProto.FLOAT, [LAYERS, B, SIZE]),
    ]
    if variant == "v1_with_mask":   # a mask input contract 1 does not have (left unused)
        inputs.append(helper.make_tensor_value_info("imu_mask", TensorProto.FLOAT, [B, "T", 6]))
    # symbolic_dims: the fixed output sizes left symbolic (as exporters often leave them);
    # wrong_output_shape: the same, but the graph really makes 12 joints (ONNX Runtime infers it).
    J = "J" if variant in ("symbolic_dims", "wrong_output_shape") else 24
    outputs = [
        helper.make_tensor_value_info("joint_rotations", TensorProto.FLOAT, [B, "T", J, 3, 3]),
        helper.make_tensor_value_info("root_velocity", TensorProto.FLOAT, [B, "T", 3]),
        helper.make_tensor_value_info("foot_contact", TensorProto.FLOAT, [B, "T", 2]),
        helper.make_tensor_value_info("state_out_h", TensorProto.FLOAT, [LAYERS, B, SIZE]),
        helper.make_tensor_value_info("state_out_c", TensorProto.FLOAT, [LAYERS, B, SIZE]),
    ]

    const = _const
    inits = [
        const("shape5", [0, 0, 6, 3, 3]),
        const("tile", [1, 1, 2 if variant == "wrong_output_shape" else 4, 1, 1]),
        const("axes23", [2, 3]),
        const("axis1", 1),
        const("axes1", [1]),
        const("axes2", [2]),
        const("ones3", np.ones(3, np.float32), np.float32),
        const("start0", [0]),
        const("end2", [2]),
        const("half", np.float32(0.5), np.float32),
        const("one", np.float32(1.0), np.float32),
        const("shape1b1", [1, -1, 1]),
    ]
    nodes = [
        helper.make_node("Reshape", [ori_name, "shape5"], ["ori5"]),
        helper.make_node("Tile", ["ori5", "tile"], ["joint_rotations"]),
        helper.make_node("ReduceSum", ["imu_acceleration", "axes23"], ["a"], keepdims=0),  # [B,T]
        helper.make_node("CumSum", ["a", "axis1"], ["s"]),                                 # [B,T]
        helper.make_node("ReduceMean", ["state_in_h"], ["c"], axes=[0, 2], keepdims=0),    # [B]
        helper.make_node("Unsqueeze", ["c", "axes1"], ["c1"]),                             # [B,1]
        helper.make_node("Add", ["s", "c1"], ["v"]),                                       # [B,T]
        helper.make_node("Unsqueeze", ["v", "axes2"], ["v1"]),                             # [B,T,1]
        helper.make_node("Mul", ["v1", "ones3"], ["root_velocity"]),                      # [B,T,3]
        helper.make_node("Slice", ["root_velocity", "start0", "end2", "axes2"], ["rv2"]),
        helper.make_node("Sigmoid", ["rv2"], ["foot_contact"]),
        helper.make_node("ReduceSum", ["a", "axes1"], ["total"], keepdims=0),             # [B]
        helper.make_node("Reshape", ["total", "shape1b1"], ["total3"]),                    # [1,B,1]
        helper.make_node("Add", ["state_in_h", "total3"], ["state_out_h"]),
        helper.make_node("Mul", ["state_in_c", "half"], ["c_half"]),
        helper.make_node("Add", ["c_half", "one"], ["state_out_c"]),
    ]
    if variant == "rank_nine_output":
        # foot_contact declared [B, T, 2] but reshaped at run time to rank 9: the new shape's
        # length depends on a data-dependent Slice end (Size(state_in_h) + 1 = 9 at the probe),
        # so no static inference can see the rank and only the probe run catches it.
        inits += [const("six_ones", [1] * 6), const("one_i", [1]), const("zero_i", [0])]
        nodes = [n for n in nodes if n.output[0] != "foot_contact"] + [
            helper.make_node("Sigmoid", ["rv2"], ["contact3"]),
            helper.make_node("Shape", ["contact3"], ["contact_shape"]),
            helper.make_node("Concat", ["six_ones", "contact_shape"], ["shape9"], axis=0),
            helper.make_node("Size", ["state_in_h"], ["state_size"]),
            helper.make_node("Reshape", ["state_size", "one_i"], ["state_size1"]),
            helper.make_node("Add", ["state_size1", "one_i"], ["end9"]),
            helper.make_node("Slice", ["shape9", "zero_i", "end9"], ["shape_dyn"]),
            helper.make_node("Reshape", ["contact3", "shape_dyn"], ["foot_contact"]),
        ]
    if variant == "fails_on_impact":
        # A valid model whose inference fails at run time for some inputs (as a GPU out of memory
        # or a broken operator would): any acceleration above 50 m/s^2 makes foot_contact's
        # Reshape ask for 3 values per frame where there are 2. The probe (zero acceleration) runs.
        inits += [const("fifty", np.float32(50.0), np.float32), const("last_axis", [0, 0, 1])]
        nodes = [n for n in nodes if n.output[0] != "foot_contact"] + [
            helper.make_node("Sigmoid", ["rv2"], ["contact3"]),
            helper.make_node("Abs", ["imu_acceleration"], ["acc_abs"]),
            helper.make_node("ReduceMax", ["acc_abs"], ["acc_max"], keepdims=0),
            helper.make_node("Greater", ["acc_max", "fifty"], ["impact"]),
            helper.make_node("Cast", ["impact"], ["impact_i"], to=TensorProto.INT64),
            helper.make_node("Mul", ["last_axis", "impact_i"], ["extra"]),
            helper.make_node("Shape", ["contact3"], ["contact_shape"]),
            helper.make_node("Add", ["contact_shape", "extra"], ["asked_shape"]),
            helper.make_node("Reshape", ["contact3", "asked_shape"], ["foot_contact"]),
        ]
    override = {}
    if variant == "missing_metadata":
        md = {}
    else:
        if variant == "missing_joint_names":
            override["joint_names"] = None
        if variant == "wrong_version":
            override["contract_version"] = "9"
        if variant == "state_mismatch":
            override["state_layers"] = "3"
        if variant == "int8_precision":
            override["precision"] = "int8"
        if variant == "unknown_precision":
            override["precision"] = "bf16"
        if variant in ("stride_scaled", "stride_height_only", "stride_bad_exponent"):
            override["training_height"] = "1.70"
        if variant == "stride_scaled":
            override["stride_exponent"] = "0.6"
        if variant == "stride_bad_exponent":
            override["stride_exponent"] = "3"
        if variant == "wrong_joint_name":
            names = list(JOINTS)
            names[18] = "left_forearm"
            override["joint_names"] = ",".join(names)
        md = metadata(**override)
    return _model(nodes, inputs, outputs, inits, md)


def write_all(outdir):
    os.makedirs(outdir, exist_ok=True)
    paths = {}
    for v in VARIANTS:
        paths[v] = os.path.join(outdir, v + ".onnx")
        model = build(v)
        checker.check_model(model)
        save(model, paths[v])
    paths["not_onnx"] = os.path.join(outdir, "not_onnx.onnx")
    with open(paths["not_onnx"], "w") as f:
        f.write("this is not an ONNX model\n")
    return paths


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: make_onnx_fixtures.py OUTDIR")
    for name, path in write_all(sys.argv[1]).items():
        print(path)
