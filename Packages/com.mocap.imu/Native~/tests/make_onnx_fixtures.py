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
tests check. The other variants break the contract in one way each; the engine must refuse them
with a message naming the difference. Needs only the `onnx` Python package (Debian python3-onnx).
"""
import os
import sys

import numpy as np
from onnx import TensorProto, helper, save

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
LAYERS, SIZE = 2, 4

VARIANTS = ["valid", "wrong_input_name", "wrong_rank", "missing_metadata", "missing_joint_names",
            "wrong_version", "state_mismatch", "fixed_batch", "wrong_joint_name", "symbolic_dims",
            "wrong_output_shape", "rank_nine_output", "fails_on_impact"]


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


def build(variant="valid"):
    """The ModelProto of one variant."""
    ori_name = "imu_orient" if variant == "wrong_input_name" else "imu_orientation"
    B = 1 if variant == "fixed_batch" else "B"
    ori_shape = [B, "T", 54] if variant == "wrong_rank" else [B, "T", 6, 3, 3]
    inputs = [
        helper.make_tensor_value_info(ori_name, TensorProto.FLOAT, ori_shape),
        helper.make_tensor_value_info("imu_acceleration", TensorProto.FLOAT, [B, "T", 6, 3]),
        helper.make_tensor_value_info("state_in_h", TensorProto.FLOAT, [LAYERS, B, SIZE]),
        helper.make_tensor_value_info("state_in_c", TensorProto.FLOAT, [LAYERS, B, SIZE]),
    ]
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

    def const(name, values, dtype=np.int64):
        arr = np.asarray(values, dtype=dtype)
        return helper.make_tensor(name, TensorProto.INT64 if dtype == np.int64 else TensorProto.FLOAT,
                                  arr.shape, arr.reshape(-1).tolist())

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
    graph = helper.make_graph(nodes, "mocap_fixture", inputs, outputs, inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)],
                              producer_name="make_onnx_fixtures")
    model.ir_version = 7
    override = {}
    if variant == "missing_metadata":
        md = {}
    else:
        if variant == "missing_joint_names":
            override["joint_names"] = None
        if variant == "wrong_version":
            override["contract_version"] = "2"
        if variant == "state_mismatch":
            override["state_layers"] = "3"
        if variant == "wrong_joint_name":
            names = list(JOINTS)
            names[18] = "left_forearm"
            override["joint_names"] = ",".join(names)
        md = metadata(**override)
    helper.set_model_props(model, md)
    return model


def write_all(outdir):
    os.makedirs(outdir, exist_ok=True)
    paths = {}
    for v in VARIANTS:
        paths[v] = os.path.join(outdir, v + ".onnx")
        save(build(v), paths[v])
    paths["not_onnx"] = os.path.join(outdir, "not_onnx.onnx")
    with open(paths["not_onnx"], "w") as f:
        f.write("this is not an ONNX model\n")
    return paths


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: make_onnx_fixtures.py OUTDIR")
    for name, path in write_all(sys.argv[1]).items():
        print(path)
