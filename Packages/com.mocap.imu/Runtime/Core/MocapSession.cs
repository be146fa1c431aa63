using System;

namespace Mocap.Imu
{
    /// <summary>What a poll or drain found.</summary>
    public enum MocapPollResult
    {
        /// <summary>New frames were returned.</summary>
        Frames = 0,
        /// <summary>Nothing new since the previous poll/drain (not a failure).</summary>
        NoData = 1,
        /// <summary>A replay has delivered and drained everything.</summary>
        EndOfStream = 2,
    }

    /// <summary>
    /// One sensor set (up to <see cref="MaxSensors"/> sensors, one character): a serial port, a HID receiver or a capture replay, turned by the
    /// engine into synchronised, calibrated frames on its own threads.
    /// </summary>
    /// <remarks>
    /// <para>Lifecycle: <see cref="Open"/> opens the source (errors name the port or file), then
    /// calibration may be loaded or scheduled, then <see cref="Start"/> runs the engine threads.
    /// <see cref="Stop"/> ends them; a later <see cref="Start"/> reopens the same source with the
    /// calibration in use at the stop (not for a session that records a capture: that Start
    /// throws rather than overwrite the recording). <see cref="Dispose"/> frees everything.</para>
    /// <para>Threads: poll and drain from one thread (in Unity the main thread). Calibration,
    /// reports and statistics may be called from any thread. The engine never calls back into
    /// managed code, so no Unity code runs off the main thread.</para>
    /// <para>Allocation: <see cref="PollLatest"/>, <see cref="Drain"/>, <see cref="GetStats"/> and
    /// the report getters allocate nothing; exceptions and the string properties do.</para>
    /// <para>The pose model (<see cref="MocapModel"/>) and its characters (<see cref="MocapSolver"/>)
    /// are separate objects: a session added to a solver as a character feeds it its frames
    /// (polling, draining or stopping the session then throws until the solver is disposed), and
    /// several sessions feed several characters.</para>
    /// </remarks>
    public sealed class MocapSession : IDisposable
    {
        /// <summary>The most sensors one session carries (MOCAP_MAX_SENSORS).</summary>
        public const int MaxSensors = 16;

        readonly SessionConfig _config;
        SessionHandle _handle;
        bool _running;
        bool _ended;

        MocapSession(SessionConfig config, SessionHandle handle)
        {
            _config = config;
            _handle = handle;
        }

        /// <summary>
        /// Validate the config and open its source. Nothing runs yet: schedule or set
        /// calibration, then <see cref="Start"/>.
        /// </summary>
        /// <exception cref="MocapException">The engine refused the config or could not open the
        /// source; the message is the engine's, naming the port or file.</exception>
        public static MocapSession Open(SessionConfig config)
        {
            if (config == null) throw new ArgumentNullException(nameof(config));
            MocapEngine.EnsureCompatible();
            var own = config.Clone();
            return new MocapSession(own, OpenHandle(own));
        }

        /// <summary>A copy of the configuration the session was opened with.</summary>
        public SessionConfig Config => _config.Clone();

        /// <summary>The session's sensors (its config's sensor set); frames and reports list them in this order.</summary>
        public int SensorCount => _config.Sensors.Count;

        /// <summary>The segment of sensor <paramref name="index"/> (config order).</summary>
        public MocapSegment SegmentOf(int index) => _config.Sensors[index].Segment;

        /// <summary>The engine threads are running.</summary>
        public bool IsRunning => _running;

        /// <summary>A poll or drain has reported the end of a replay.</summary>
        public bool IsEndOfStream => _ended;

        /// <summary>Start the engine's reader and processing threads.</summary>
        /// <exception cref="InvalidOperationException">A Start after <see cref="Stop"/> of a session
        /// that records (<see cref="SessionConfig.CapturePath"/> set): reopening would overwrite
        /// that capture. Open a new session with another CapturePath instead.</exception>
        public void Start()
        {
            ThrowIfDisposed();
            if (_running) return;
            if (_handle == null)
            {
                // Restart after Stop: reopen the source and keep the calibration we had. Not with
                // a recording: reopening would start the capture writer on the same file again,
                // and it truncates it, erasing what the first run recorded.
                if (!string.IsNullOrEmpty(_config.CapturePath))
                    throw new InvalidOperationException(
                        $"the capture at {_config.CapturePath} would be overwritten: a session that records " +
                        "cannot be started again; open a new session with another CapturePath");
                var calibration = _stoppedCalibration;
                var handle = OpenHandle(_config);
                try
                {
                    // An engine that never calibrated has nothing worth restoring.
                    if ((calibration.ValidMask | calibration.HeadingMask) != 0)
                        SetCalibration(handle, calibration);
                }
                catch
                {
                    handle.Dispose();
                    throw;
                }
                _handle = handle;
                _ended = false;
            }
            NativeMethods.Check(NativeMethods.mocap_session_start(_handle));
            _running = true;
        }

        /// <summary>
        /// Stop the engine threads (promptly, even while a device read blocks) and close the
        /// source; a recording capture is flushed and closed. Returns the session's final stats:
        /// <see cref="MocapSessionStats.CaptureError"/> is not Ok when the recording failed (a full
        /// disk, also at its last flush or close) and LastError then names the file and the cause;
        /// CaptureBytesWritten is the file's final size. <see cref="GetStats"/> keeps returning
        /// them until the next <see cref="Start"/>. The calibration is kept for a later Start;
        /// scheduled calibration steps are dropped.
        /// </summary>
        public unsafe MocapSessionStats Stop()
        {
            if (_handle == null) return _stoppedStats;
            // The solver holds the native session: closing it here would only be deferred, and a
            // later Start would open a new one the solver never sees.
            if (ConsumingSolver != null)
                throw new InvalidOperationException("a MocapSolver consumes this session: dispose the solver first");
            // Its status is the capture's outcome, which the final stats carry too.
            NativeMethods.mocap_session_stop(_handle);
            // After the stop: a calibration step can still finish on the bytes read before it.
            _stoppedCalibration = Calibration;
            MocapSessionStats stats;
            NativeMethods.Check(NativeMethods.mocap_session_get_stats(_handle, &stats));
            _stoppedStats = stats;
            _handle.Dispose();
            _handle = null;
            _running = false;
            return stats;
        }

        CalibrationData _stoppedCalibration;
        MocapSessionStats _stoppedStats;
        bool _disposed;

        /// <summary>
        /// Stop and free the native session. A session that records (<see cref="SessionConfig.CapturePath"/>)
        /// only reports a last flush or close that failed (a full disk) through <see cref="Stop"/>'s
        /// stats: call Stop first to learn whether the capture is complete; Dispose cannot report it.
        /// </summary>
        public void Dispose()
        {
            if (_disposed) return;
            _disposed = true;
            _handle?.Dispose();
            _handle = null;
            _running = false;
        }

        /// <summary>
        /// Copy the newest frame into <paramref name="frame"/>, skipping older ones. Returns
        /// <see cref="MocapPollResult.NoData"/> when nothing is newer than the previous poll
        /// (frame is left as it was) and <see cref="MocapPollResult.EndOfStream"/> once a replay
        /// is finished and drained (also when its file stopped reading part way: the stats'
        /// LastError then names the file and the cause). Allocates nothing.
        /// </summary>
        public unsafe MocapPollResult PollLatest(ref MocapFrame frame)
        {
            ThrowIfConsumed();
            MocapFrame latest;
            var status = NativeMethods.mocap_session_poll_latest(Handle, &latest);
            if (status == MocapStatus.Ok)
            {
                frame = latest;
                return MocapPollResult.Frames;
            }
            return NotReady(status);
        }

        /// <summary>
        /// Copy every frame produced since the previous drain, oldest first, into
        /// <paramref name="destination"/> (up to its length); <paramref name="count"/> receives
        /// how many. Frames that do not fit stay queued for the next call. Allocates nothing.
        /// </summary>
        public unsafe MocapPollResult Drain(Span<MocapFrame> destination, out int count)
        {
            count = 0;
            ThrowIfConsumed();
            if (destination.Length == 0)
                throw new ArgumentException("the destination holds no frames", nameof(destination));
            uint n = 0;
            MocapStatus status;
            fixed (MocapFrame* frames = destination)
                status = NativeMethods.mocap_session_drain(Handle, frames, (uint)destination.Length, &n);
            count = (int)n;
            if (status == MocapStatus.Ok) return MocapPollResult.Frames;
            return NotReady(status);
        }

        /// <summary>Counters and health of the session (after <see cref="Stop"/>: its final
        /// stats). Allocates nothing.</summary>
        public unsafe MocapSessionStats GetStats()
        {
            if (_handle == null && !_disposed) return _stoppedStats;
            MocapSessionStats stats;
            NativeMethods.Check(NativeMethods.mocap_session_get_stats(Handle, &stats));
            return stats;
        }

        /// <summary>
        /// One counter by key, as <see cref="GetStats"/> reports it: counters added in later minor
        /// API versions are keys, not new struct fields. Throws <see cref="MocapException"/>
        /// (Unsupported) for a key the loaded library does not know. Allocates nothing.
        /// </summary>
        public unsafe ulong GetCounter(SessionCounter counter)
        {
            ulong value;
            NativeMethods.Check(NativeMethods.mocap_session_get_counter(Handle, (int)counter, &value));
            return value;
        }

        /// <summary>
        /// Schedule a calibration step over [startSeconds, startSeconds + durationSeconds] of the
        /// session clock (frame time; a replay's clock is its recorded receive time). Steps
        /// queue (up to 8), so a replay's heading and T-pose windows can both be scheduled
        /// before <see cref="Start"/>. Follow it with <see cref="GetCalibrationReport(CalibrationStep)"/>.
        /// </summary>
        public void ScheduleCalibration(CalibrationStep step, double startSeconds, float durationSeconds)
        {
            NativeMethods.Check(NativeMethods.mocap_calibration_schedule(
                Handle, (int)step, startSeconds, durationSeconds));
        }

        /// <summary>Run a calibration step from the next frame on, for durationSeconds (0.2..15).</summary>
        public void BeginCalibration(CalibrationStep step, float durationSeconds)
        {
            ScheduleCalibration(step, -1.0, durationSeconds);
        }

        /// <summary>
        /// Yaw-only re-alignment against drift: the user stands still facing forward. Follow it
        /// with <see cref="GetCalibrationReport(CalibrationStep)"/> for <see cref="CalibrationStep.HeadingReset"/>.
        /// </summary>
        public void ResetHeading(float durationSeconds = 1f)
        {
            BeginCalibration(CalibrationStep.HeadingReset, durationSeconds);
        }

        /// <summary>The step collecting now, or else the last one that finished.</summary>
        public unsafe CalibrationReport GetCalibrationReport()
        {
            CalibrationReport report;
            NativeMethods.Check(NativeMethods.mocap_calibration_get_report(Handle, &report));
            return report;
        }

        /// <summary>The latest request of one step: waiting, collecting or its result.</summary>
        public unsafe CalibrationReport GetCalibrationReport(CalibrationStep step)
        {
            CalibrationReport report;
            NativeMethods.Check(NativeMethods.mocap_calibration_get_step_report(Handle, (int)step, &report));
            return report;
        }

        /// <summary>
        /// The calibration in use (after <see cref="Stop"/>: the one it had when it stopped). Setting
        /// it (e.g. one loaded with <see cref="CalibrationData.Load"/>) replaces it from the next frame on.
        /// </summary>
        public unsafe CalibrationData Calibration
        {
            get
            {
                // Stopped: what it was when the session stopped (it is restored by Start).
                if (_handle == null && !_disposed) return _stoppedCalibration;
                CalibrationData calibration;
                NativeMethods.Check(NativeMethods.mocap_calibration_get(Handle, &calibration));
                return calibration;
            }
            set
            {
                SetCalibration(Handle, value);
            }
        }

        SessionHandle Handle
        {
            get
            {
                ThrowIfDisposed();
                // One read: another thread's Stop() may clear the field meanwhile. A call already
                // holding the handle then completes (SafeHandle defers the close) or gets
                // ObjectDisposedException, never a null handle.
                var handle = System.Threading.Volatile.Read(ref _handle);
                if (handle == null)
                    throw new InvalidOperationException("the session is stopped; Start() reopens it");
                return handle;
            }
        }

        /// <summary>The solver this session feeds as a character (it then owns the frames), or null.</summary>
        internal MocapSolver ConsumingSolver { get; set; }

        /// <summary>The native handle, for the solver to reference (throws when stopped or disposed).</summary>
        internal SessionHandle NativeHandle => Handle;

        void ThrowIfConsumed()
        {
            if (ConsumingSolver != null)
                throw new InvalidOperationException(
                    "a MocapSolver consumes this session's frames: poll or drain the solver instead");
        }

        void ThrowIfDisposed()
        {
            if (_disposed) throw new ObjectDisposedException(nameof(MocapSession));
        }

        MocapPollResult NotReady(MocapStatus status)
        {
            if (status == MocapStatus.NoData) return MocapPollResult.NoData;
            if (status == MocapStatus.EndOfStream)
            {
                _ended = true;
                return MocapPollResult.EndOfStream;
            }
            throw NativeMethods.Failure(status);
        }

        static unsafe SessionHandle OpenHandle(SessionConfig config)
        {
            config.ToNative(out var native);
            IntPtr session;
            var status = NativeMethods.mocap_session_open(&native, out session);
            if (status != MocapStatus.Ok) throw NativeMethods.Failure(status);
            return new SessionHandle(session);
        }

        static unsafe void SetCalibration(SessionHandle handle, in CalibrationData calibration)
        {
            var copy = calibration.WithStructSize();
            NativeMethods.Check(NativeMethods.mocap_calibration_set(handle, &copy));
        }
    }
}
