// P/Invoke declarations of the pose model and solver part of the C API (Native~/include/mocap_imu.h,
// "Pose model and solver"). The same rules as NativeMethods: blittable parameters only (struct
// pointers, integers, SafeHandles), paths as NUL-terminated UTF-8 byte pointers, Cdecl.

using System;
using System.Runtime.InteropServices;

namespace Mocap.Imu
{
    internal static unsafe class NativeSolverMethods
    {
        const string Library = NativeMethods.Library;
        const CallingConvention Cdecl = CallingConvention.Cdecl;

        /// <summary>MOCAP_JOINT_COUNT.</summary>
        internal const int JointCount = 24;

        /// <summary>MOCAP_MAX_CHARACTERS.</summary>
        internal const int MaxCharacters = 64;

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_model_options_defaults(NativeModelOptions* options);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_model_open(byte* path, NativeModelOptions* options,
                                                            out IntPtr model);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_model_get_info(ModelHandle model, NativeModelInfo* info);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_model_get_stride_scaling(ModelHandle model,
                                                                          float* trainingHeight,
                                                                          float* strideExponent);

        // Takes the raw pointer: only ModelHandle.ReleaseHandle calls it.
        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern void mocap_model_close(IntPtr model);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_config_defaults(NativeSolverConfig* config);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_open(ModelHandle model, NativeSolverConfig* config,
                                                             out IntPtr solver);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_add_character(SolverHandle solver,
                                                                      SessionHandle session,
                                                                      int* character);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_start(SolverHandle solver);

        // Takes the raw pointer: only SolverHandle.ReleaseHandle calls it.
        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern void mocap_solver_close(IntPtr solver);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_poll_latest(SolverHandle solver, int character,
                                                                    MocapPose* pose);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_drain(SolverHandle solver, int character,
                                                              MocapPose* poses, uint capacity,
                                                              uint* count);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_reset_character(SolverHandle solver, int character);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_set_character_height(SolverHandle solver,
                                                                             int character, float heightM);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_set_smoothing_delay(SolverHandle solver, int frames);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_set_foot_pinning(SolverHandle solver, float slideMetresPerSecond);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_set_pose_limits(SolverHandle solver, float toleranceDegrees);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_set_chest_follow(SolverHandle solver, float share);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_get_stats(SolverHandle solver, int character,
                                                                  MocapSolverStats* stats);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_solver_get_counter(SolverHandle solver, int character, int counter,
                                                                    ulong* value);
    }
}
