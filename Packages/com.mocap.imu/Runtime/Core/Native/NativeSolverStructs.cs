// Layout mirrors of the pose model and solver structs (Native~/include/mocap_imu.h, "Pose model
// and solver", API version 2). Only the mirrors that NativeLayoutTests needs to check every struct
// the engine reports: the solver's C# API (bindings, wrappers) is a separate piece of work and
// will build on these.

using System.Runtime.InteropServices;

namespace Mocap.Imu
{
    [NativeName("mocap_model_options")]
    [StructLayout(LayoutKind.Sequential)]
    internal unsafe struct NativeModelOptions
    {
        [NativeName("struct_size")] public uint StructSize;
        [NativeName("execution_provider")] public int ExecutionProvider;
        [NativeName("intra_op_threads")] public int IntraOpThreads;
        [NativeName("optimization_level")] public int OptimizationLevel;
        [NativeName("cuda_device")] public int CudaDevice;
        [NativeName("onnxruntime_path")] public fixed byte OnnxRuntimePath[NativeMethods.PathMax];
    }

    [NativeName("mocap_model_info")]
    [StructLayout(LayoutKind.Sequential)]
    internal unsafe struct NativeModelInfo
    {
        internal const int JointCount = 24;

        [NativeName("contract_version")] public int ContractVersion;
        [NativeName("frame_rate")] public float FrameRate;
        [NativeName("state_layers")] public int StateLayers;
        [NativeName("state_size")] public int StateSize;
        [NativeName("joint_parents")] public fixed int JointParents[JointCount];
        [NativeName("rest_offsets")] public fixed float RestOffsets[JointCount * 3];
        [NativeName("joint_names")] public fixed byte JointNames[JointCount * 32];
        [NativeName("precision")] public fixed byte Precision[8];
        [NativeName("model_name")] public fixed byte ModelName[128];
    }

    [NativeName("mocap_solver_config")]
    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeSolverConfig
    {
        [NativeName("struct_size")] public uint StructSize;
        [NativeName("contact_threshold")] public float ContactThreshold;
        [NativeName("floor_height")] public float FloorHeight;
        [NativeName("drift_correction")] public int DriftCorrection;
        [NativeName("require_calibration")] public int RequireCalibration;
        [NativeName("smoothing_min_cutoff_hz")] public float SmoothingMinCutoffHz;
        [NativeName("smoothing_beta")] public float SmoothingBeta;
    }

    [NativeName("mocap_pose")]
    [StructLayout(LayoutKind.Sequential)]
    internal unsafe struct NativePose
    {
        internal const int JointCount = 24;

        [NativeName("sequence")] public ulong Sequence;
        [NativeName("frame_sequence")] public ulong FrameSequence;
        [NativeName("time_s")] public double TimeSeconds;
        [NativeName("character")] public uint Character;
        [NativeName("flags")] public uint Flags;
        [NativeName("joint_rotations")] public fixed float JointRotations[JointCount * 4];
        [NativeName("joint_positions")] public fixed float JointPositions[JointCount * 3];
        [NativeName("root_position")] public fixed float RootPosition[3];
        [NativeName("root_velocity")] public fixed float RootVelocity[3];
        [NativeName("foot_contact")] public fixed float FootContact[2];
        [NativeName("newest_receive_ns")] public long NewestReceiveNs;
        [NativeName("frame_emitted_ns")] public long FrameEmittedNs;
        [NativeName("pose_emitted_ns")] public long PoseEmittedNs;
    }
}
