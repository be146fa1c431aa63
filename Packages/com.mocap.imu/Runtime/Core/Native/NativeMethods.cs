// P/Invoke declarations of the engine's C API (Native~/include/mocap_imu.h).
//
// Rules kept here so that the hot path never allocates and IL2CPP can compile every call:
//  - only blittable parameters: pointers to the mirrored structs, integers, SafeHandle;
//  - strings go in as NUL-terminated UTF-8 byte pointers and come out as IntPtr decoded by
//    NativeText, never through the marshaller's string conversions;
//  - Cdecl everywhere (the header declares no calling convention; on x64 it is moot, on
//    32-bit Windows it is what a plain C export uses).

using System;
using System.Runtime.CompilerServices;
using System.Runtime.InteropServices;
using System.Text;

// The NUnit tests (plain dotnet and Unity's Test Runner) check layouts through internals.
[assembly: InternalsVisibleTo("Mocap.Imu.Core.Tests")]

namespace Mocap.Imu
{
    internal static unsafe class NativeMethods
    {
        /// <summary>
        /// The library name without prefix or extension: the runtime adds "lib"/".so" on Linux,
        /// ".dll" on Windows and "lib"/".dylib" on macOS (Unity also finds a .bundle), and IL2CPP
        /// on desktop links it the same way.
        /// </summary>
        internal const string Library = "mocap_imu";

        /// <summary>MOCAP_API_VERSION (major) these bindings mirror.</summary>
        internal const int ApiVersion = 6;

        /// <summary>MOCAP_API_VERSION_MINOR these bindings need at least.</summary>
        internal const int ApiMinorVersion = 6;

        internal const int PathMax = 260;

        const CallingConvention Cdecl = CallingConvention.Cdecl;

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern IntPtr mocap_last_error();

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern IntPtr mocap_status_name(int status);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern int mocap_api_version();

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern int mocap_api_version_minor();

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern IntPtr mocap_humanoid_bone_name(int joint);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern IntPtr mocap_version_string();

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern int mocap_segment_count();

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern IntPtr mocap_segment_name(int segment);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern int mocap_segment_find(byte* name);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern int mocap_segment_joint(int segment);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern int mocap_segment_default_node(int segment);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_config_defaults(NativeSessionConfig* config);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_session_open(NativeSessionConfig* config,
                                                              out IntPtr session);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_session_start(SessionHandle session);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_session_stop(SessionHandle session);

        // Takes the raw pointer: only SessionHandle.ReleaseHandle calls it.
        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern void mocap_session_close(IntPtr session);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_session_poll_latest(SessionHandle session,
                                                                     MocapFrame* frame);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_session_drain(SessionHandle session,
                                                               MocapFrame* frames, uint capacity,
                                                               uint* count);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_session_get_stats(SessionHandle session,
                                                                   MocapSessionStats* stats);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_session_get_counter(SessionHandle session, int counter,
                                                                     ulong* value);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_calibration_schedule(SessionHandle session,
                                                                      int step, double startSeconds,
                                                                      float durationSeconds);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_calibration_get_report(
            SessionHandle session, CalibrationReport* report);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_calibration_get_step_report(
            SessionHandle session, int step, CalibrationReport* report);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_calibration_get(SessionHandle session,
                                                                 CalibrationData* calibration);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_calibration_set(SessionHandle session,
                                                                 CalibrationData* calibration);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_calibration_save(CalibrationData* calibration,
                                                                  byte* path);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_calibration_load(byte* path,
                                                                  CalibrationData* calibration);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern NativeFieldLayout* mocap_struct_layout(uint* count);

        /// <summary>
        /// Throws a <see cref="MocapException"/> with the engine's error text unless status is
        /// Ok. Must run on the thread that made the failing call: the text is thread-local.
        /// </summary>
        internal static void Check(MocapStatus status)
        {
            if (status != MocapStatus.Ok) throw Failure(status);
        }

        /// <summary>The exception for a failed call, carrying mocap_last_error() of this thread.</summary>
        internal static MocapException Failure(MocapStatus status)
        {
            return new MocapException(status, NativeText.FromPointer(mocap_last_error()));
        }
    }

    /// <summary>UTF-8 conversions for the C API without marshaller allocations on hot paths.</summary>
    internal static unsafe class NativeText
    {
        /// <summary>Decode a NUL-terminated UTF-8 string ("" for NULL).</summary>
        internal static string FromPointer(IntPtr text)
        {
            if (text == IntPtr.Zero) return string.Empty;
            byte* p = (byte*)text;
            int length = 0;
            while (p[length] != 0) length++;
            return Encoding.UTF8.GetString(p, length);
        }

        /// <summary>Decode a NUL-padded UTF-8 buffer of at most capacity bytes.</summary>
        internal static string FromBuffer(byte* buffer, int capacity)
        {
            int length = 0;
            while (length < capacity && buffer[length] != 0) length++;
            return Encoding.UTF8.GetString(buffer, length);
        }

        /// <summary>
        /// Write text as NUL-terminated UTF-8 into a fixed buffer of capacity bytes (zero-filled
        /// after the text). Throws when it does not fit, naming the field, rather than cutting a
        /// path short and opening the wrong file.
        /// </summary>
        internal static void ToBuffer(string text, byte* buffer, int capacity, string field)
        {
            var span = new Span<byte>(buffer, capacity);
            span.Clear();
            if (string.IsNullOrEmpty(text)) return;
            int bytes = Encoding.UTF8.GetByteCount(text);
            if (bytes >= capacity)
                throw new ArgumentException(
                    $"{field} is {bytes} bytes of UTF-8; the engine accepts at most {capacity - 1}",
                    field);
            if (text.IndexOf('\0') >= 0)
                throw new ArgumentException($"{field} contains a NUL character", field);
            Encoding.UTF8.GetBytes(text.AsSpan(), span);
        }

        /// <summary>A new NUL-terminated UTF-8 copy of text (for calls off the hot path).</summary>
        internal static byte[] ToNullTerminated(string text, string field)
        {
            if (text == null) throw new ArgumentNullException(field);
            if (text.IndexOf('\0') >= 0)
                throw new ArgumentException($"{field} contains a NUL character", field);
            var bytes = new byte[Encoding.UTF8.GetByteCount(text) + 1];
            Encoding.UTF8.GetBytes(text, 0, text.Length, bytes, 0);
            return bytes;
        }
    }
}
