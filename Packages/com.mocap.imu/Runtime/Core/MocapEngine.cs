using System;

namespace Mocap.Imu
{
    /// <summary>Facts about the loaded native engine.</summary>
    public static class MocapEngine
    {
        static bool _checked;

        /// <summary>"major.minor.patch" of the engine.</summary>
        public static string Version => NativeText.FromPointer(NativeMethods.mocap_version_string());

        /// <summary>MOCAP_API_VERSION (the major version) the library was built with.</summary>
        public static int ApiVersion => NativeMethods.mocap_api_version();

        /// <summary>MOCAP_API_VERSION (the major version) these bindings were written for.</summary>
        public static int BindingsApiVersion => NativeMethods.ApiVersion;

        /// <summary>The library's major.minor API version (a library older than minor versions reads as minor 0).</summary>
        public static ApiVersion LibraryApi
        {
            get
            {
                int minor;
                try { minor = NativeMethods.mocap_api_version_minor(); }
                catch (EntryPointNotFoundException) { minor = 0; }
                return new ApiVersion(NativeMethods.mocap_api_version(), minor);
            }
        }

        /// <summary>The major.minor API version these bindings were written for.</summary>
        public static ApiVersion BindingsApi => new ApiVersion(NativeMethods.ApiVersion, NativeMethods.ApiMinorVersion);

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
        /// Throws when the loaded library was built for another major API version (the struct
        /// mirrors would read garbage) or an older minor one (functions the bindings call are
        /// missing), so refuse before the first session opens.
        /// </summary>
        public static void EnsureCompatible()
        {
            if (_checked) return;
            var refusal = Mocap.Imu.ApiVersion.Refusal(BindingsApi, LibraryApi, NativeMethods.Library);
            if (refusal != null) throw new MocapException(MocapStatus.Unsupported, refusal);
            _checked = true;
        }
    }
}
