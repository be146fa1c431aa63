using System;

namespace Mocap.Imu
{
    /// <summary>
    /// The engine's C API version, major.minor. Within a major version the library only adds
    /// (functions, enum values, counter keys) and never changes a struct, so bindings written for
    /// M.m work with any library M.n where n &gt;= m, and with no library of another major.
    /// </summary>
    public readonly struct ApiVersion : IEquatable<ApiVersion>
    {
        /// <summary>Changes when a signature, a struct layout or a value's meaning changes.</summary>
        public readonly int Major;
        /// <summary>Grows when something is added.</summary>
        public readonly int Minor;

        public ApiVersion(int major, int minor)
        {
            if (major < 0 || minor < 0) throw new ArgumentOutOfRangeException(major < 0 ? nameof(major) : nameof(minor));
            Major = major;
            Minor = minor;
        }

        /// <summary>
        /// Whether bindings written for <paramref name="bindings"/> can use a library of
        /// <paramref name="library"/>: the same major, and at least the bindings' minor.
        /// </summary>
        public static bool Accepts(ApiVersion bindings, ApiVersion library) =>
            library.Major == bindings.Major && library.Minor >= bindings.Minor;

        /// <summary>Why <see cref="Accepts"/> refuses, for an error message (null when it accepts).</summary>
        public static string Refusal(ApiVersion bindings, ApiVersion library, string libraryName)
        {
            if (Accepts(bindings, library)) return null;
            if (library.Major != bindings.Major)
                return $"the native library {libraryName} has API version {library}, these bindings need " +
                       $"{bindings.Major}.x ({bindings} or newer); structs differ between major versions: " +
                       "rebuild the library or update the package";
            return $"the native library {libraryName} has API version {library}, older than these bindings' " +
                   $"{bindings}: it lacks functions they call; rebuild the library or update the package";
        }

        public bool Equals(ApiVersion other) => Major == other.Major && Minor == other.Minor;
        public override bool Equals(object obj) => obj is ApiVersion other && Equals(other);
        public override int GetHashCode() => Major * 1000 + Minor;
        public override string ToString() => $"{Major}.{Minor}";
    }
}
