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
        [NativeName("sensor_count")] public uint SensorCount;
        [NativeName("sensor_segments")] public fixed int SensorSegments[MocapSession.MaxSensors];
        [NativeName("sensor_required_mask")] public uint SensorRequiredMask;
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

    /// <summary>
    /// Counters and health of a solver (mocap_solver_stats). A frame whose inference fails (ONNX
    /// Runtime out of memory, a model that cannot run the inputs) keeps the previous pose and is
    /// counted in <see cref="RunFailures"/>; the first and latest failures keep their text.
    /// </summary>
    [NativeName("mocap_solver_stats")]
    [StructLayout(LayoutKind.Sequential)]
    public unsafe struct MocapSolverStats
    {
        /// <summary>Inference calls (one per tick that had a frame).</summary>
        [NativeName("ticks")] public ulong Ticks;
        /// <summary>Calls that batched two or more characters.</summary>
        [NativeName("batched_calls")] public ulong BatchedCalls;
        [NativeName("max_batch")] public ulong MaxBatch;
        /// <summary>Frames fed to the model.</summary>
        [NativeName("frames_solved")] public ulong FramesSolved;
        /// <summary>Frames skipped because the character was not calibrated yet.</summary>
        [NativeName("frames_uncalibrated")] public ulong FramesUncalibrated;
        /// <summary>Frames with NaN/Inf inputs: not fed, previous pose held.</summary>
        [NativeName("frames_nonfinite")] public ulong FramesNonFinite;
        /// <summary>NaN/Inf model outputs: state kept, previous pose held.</summary>
        [NativeName("outputs_nonfinite")] public ulong OutputsNonFinite;
        /// <summary>Live poses lost because the consumer was too slow.</summary>
        [NativeName("poses_dropped")] public ulong PosesDropped;
        /// <summary>Frames whose inference failed (previous pose held).</summary>
        [NativeName("run_failures")] public ulong RunFailures;
        [NativeName("solve_ns_total")] public ulong SolveNsTotal;
        [NativeName("solve_ns_max")] public ulong SolveNsMax;
        [NativeName("run_ns_total")] public ulong RunNsTotal;
        /// <summary>Status of the latest failed inference (<see cref="MocapStatus.Ok"/>: none).</summary>
        [NativeName("last_run_status")] public MocapStatus LastRunStatus;
        [NativeName("reserved")] private uint _reserved;
        [NativeName("first_run_error")] private fixed byte _firstRunError[256];
        [NativeName("last_run_error")] private fixed byte _lastRunError[256];

        /// <summary>The first failed inference's text (the model, ONNX Runtime's reason), or "". Allocates.</summary>
        public string FirstRunError
        {
            get { fixed (byte* p = _firstRunError) return NativeText.FromBuffer(p, 256); }
        }

        /// <summary>The latest failed inference's text, or "". Allocates.</summary>
        public string LastRunError
        {
            get { fixed (byte* p = _lastRunError) return NativeText.FromBuffer(p, 256); }
        }
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
