namespace Mocap.Imu
{
    /// <summary>
    /// Keys of <see cref="MocapSession.GetCounter"/> (C: mocap_session_counter). Keys are only ever
    /// added, with a minor API version; the values match the engine's header.
    /// </summary>
    public enum SessionCounter
    {
        BytesReceived = 0,
        /// <summary>HiPNUC frames with a valid CRC.</summary>
        FramesDecoded = 1,
        CrcFailures = 2,
        /// <summary>Garbage bytes discarded while resynchronising.</summary>
        BytesSkipped = 3,
        UnknownPackets = 4,
        SamplesDecoded = 5,
        SamplesRejected = 6,
        FramesEmitted = 7,
        /// <summary>Output frames lost because the consumer was too slow.</summary>
        FramesDropped = 8,
        /// <summary>Input bytes lost because processing was too slow.</summary>
        BytesDropped = 9,
        Reconnects = 10,
        CaptureBytesWritten = 11,
        ReplayChunksSkipped = 12,
        /// <summary>1 once a replayed capture turned out to end damaged or cut short, else 0.</summary>
        ReplayTailDamaged = 13,
        /// <summary>Bit s: the sensor of segment s produced a sample.</summary>
        SensorsSeenMask = 14,
    }

    /// <summary>
    /// Keys of <see cref="MocapSolver.GetCounter"/> (C: mocap_solver_counter). Keys are only ever
    /// added, with a minor API version; the values match the engine's header.
    /// </summary>
    public enum SolverCounter
    {
        Ticks = 0,
        BatchedCalls = 1,
        MaxBatch = 2,
        FramesSolved = 3,
        FramesUncalibrated = 4,
        FramesNonFinite = 5,
        OutputsNonFinite = 6,
        PosesDropped = 7,
        RunFailures = 8,
        SolveNsTotal = 9,
        SolveNsMax = 10,
        RunNsTotal = 11,
    }
}
