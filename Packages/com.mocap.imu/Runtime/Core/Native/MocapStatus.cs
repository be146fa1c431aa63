using System;

namespace Mocap.Imu
{
    /// <summary>Status codes of the engine (mocap_status). <see cref="Ok"/> is success.</summary>
    public enum MocapStatus
    {
        Ok = 0,
        /// <summary>A NULL pointer, an out-of-range value, a bad config.</summary>
        InvalidArgument = 1,
        /// <summary>Port, device or file does not exist.</summary>
        NotFound = 2,
        /// <summary>The OS refused access (e.g. not in the dialout group).</summary>
        Permission = 3,
        /// <summary>Read/write failed; disk full; device error.</summary>
        IO = 4,
        /// <summary>The device went away (unplugged).</summary>
        Disconnected = 5,
        /// <summary>A file is not what it claims (bad magic, CRC, version).</summary>
        Format = 6,
        /// <summary>The call is not valid in the session's current state.</summary>
        State = 7,
        /// <summary>Feature not compiled in or not available on this OS.</summary>
        Unsupported = 8,
        NoMemory = 9,
        /// <summary>Calibration refused: see the calibration report.</summary>
        BadCalibration = 10,
        /// <summary>Nothing new to return (not a failure for polling).</summary>
        NoData = 11,
        /// <summary>A replay has delivered everything.</summary>
        EndOfStream = 12,
        Timeout = 13,
    }

    /// <summary>
    /// An engine call failed. <see cref="Exception.Message"/> is the engine's own text (it names
    /// the port or file and the cause); <see cref="Status"/> is the code to branch on.
    /// </summary>
    public class MocapException : Exception
    {
        public MocapException(MocapStatus status, string message)
            : base(string.IsNullOrEmpty(message) ? status.ToString() : message)
        {
            Status = status;
        }

        public MocapException(MocapStatus status, string message, Exception inner)
            : base(string.IsNullOrEmpty(message) ? status.ToString() : message, inner)
        {
            Status = status;
        }

        /// <summary>The engine's status code.</summary>
        public MocapStatus Status { get; }
    }
}
