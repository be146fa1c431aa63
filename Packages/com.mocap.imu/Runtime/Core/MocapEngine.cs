using System;

namespace Mocap.Imu
{
    /// <summary>Facts about the loaded native engine.</summary>
    public static class MocapEngine
    {
        static bool _checked;

        /// <summary>"major.minor.patch" of the engine.</summary>
        public static string Version => NativeText.FromPointer(NativeMethods.mocap_version_string());

        /// <summary>MOCAP_API_VERSION the library was built with.</summary>
        public static int ApiVersion => NativeMethods.mocap_api_version();

        /// <summary>MOCAP_API_VERSION these bindings were written for.</summary>
        public static int BindingsApiVersion => NativeMethods.ApiVersion;

        /// <summary>The engine's name of a segment, e.g. "left_wrist".</summary>
        public static string SegmentName(MocapSegment segment)
        {
            var name = NativeMethods.mocap_segment_name((int)segment);
            if (name == IntPtr.Zero) throw new ArgumentOutOfRangeException(nameof(segment));
            return NativeText.FromPointer(name);
        }

        /// <summary>The engine's constant name of a status, e.g. "MOCAP_ERR_NOT_FOUND".</summary>
        public static string StatusName(MocapStatus status) =>
            NativeText.FromPointer(NativeMethods.mocap_status_name((int)status));

        /// <summary>
        /// Throws when the loaded library was built for another API version: the struct
        /// mirrors would then read garbage, so refuse before the first session opens.
        /// </summary>
        public static void EnsureCompatible()
        {
            if (_checked) return;
            int version = ApiVersion;
            if (version != NativeMethods.ApiVersion)
                throw new MocapException(MocapStatus.Unsupported,
                    $"the native library {NativeMethods.Library} has API version {version}, " +
                    $"these bindings need {NativeMethods.ApiVersion}; rebuild or update the package");
            _checked = true;
        }
    }
}
