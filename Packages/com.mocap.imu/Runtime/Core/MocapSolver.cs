using System;
using System.Collections.Generic;

namespace Mocap.Imu
{
    /// <summary>
    /// How a solver turns model outputs into poses (mocap_solver_config). A new instance holds the
    /// engine's defaults.
    /// </summary>
    public sealed class SolverConfig
    {
        /// <summary>The engine's defaults (0.5 contact threshold, floor at 0, drift correction on,
        /// only calibrated frames solved, output smoothing 1 Hz / 6).</summary>
        public unsafe SolverConfig()
        {
            MocapEngine.EnsureCompatible();
            NativeSolverConfig native;
            NativeMethods.Check(NativeSolverMethods.mocap_solver_config_defaults(&native));
            ContactThreshold = native.ContactThreshold;
            FloorHeight = native.FloorHeight;
            DriftCorrection = native.DriftCorrection != 0;
            RequireCalibration = native.RequireCalibration != 0;
            SmoothingMinCutoffHz = native.SmoothingMinCutoffHz;
            SmoothingBeta = native.SmoothingBeta;
        }

        /// <summary>Foot contact probability that counts as planted, 0..1.</summary>
        public float ContactThreshold { get; set; }
        /// <summary>Floor height, model frame, metres.</summary>
        public float FloorHeight { get; set; }
        /// <summary>Planted feet hold the root back from sliding and stand on the floor.</summary>
        public bool DriftCorrection { get; set; }
        /// <summary>Only calibrated frames are solved.</summary>
        public bool RequireCalibration { get; set; }
        /// <summary>Output smoothing (a one-euro filter per joint): cut-off frequency in Hz for a
        /// joint at rest. Lower is smoother; 0 turns smoothing off (the model's raw output).</summary>
        public float SmoothingMinCutoffHz { get; set; }
        /// <summary>How much the cut-off rises with joint speed (Hz per rad/s): higher lets fast
        /// motion through with less lag.</summary>
        public float SmoothingBeta { get; set; }
        /// <summary>Most frames <see cref="SmoothingDelayFrames"/> takes (MOCAP_SMOOTHING_DELAY_MAX).</summary>
        public const int MaxSmoothingDelayFrames = 4;
        /// <summary>Smoothing that waits: with N &gt; 0 each pose is the centred average of its
        /// joint rotations over the N frames before and after it (N = 1: 1/4, 1/2, 1/4), handed
        /// out N frames later and stamped with its own frame, in place of the one-euro filter. It
        /// takes out the network's frame-to-frame noise without lag against its own frame, for N
        /// frames of latency: for recording takes and streaming, not for a VR avatar. 0 (the
        /// default) keeps the one-euro filter.</summary>
        public int SmoothingDelayFrames { get; set; }
        /// <summary>Fastest <see cref="FootPinSlideSpeed"/> (MOCAP_FOOT_PIN_SLIDE_MAX), m/s.</summary>
        public const float MaxFootPinSlideSpeed = 1.0f;
        /// <summary>Foot pinning: with a speed &gt; 0 (m/s) a planted foot stays where it touched
        /// down, the leg bent to reach it, sliding at most this fast after the predicted foot and
        /// never more than 5 cm from it; the root and the rest of the body are unchanged. 0.06 gives
        /// planted feet about the motion capture's own slide. 0 (the default) shows the predicted
        /// legs as they are.</summary>
        public float FootPinSlideSpeed { get; set; }
        /// <summary>Tightest <see cref="PoseLimitDegrees"/> besides 0 (MOCAP_POSE_LIMITS_MIN_DEG).</summary>
        public const float MinPoseLimitDegrees = 1.0f;
        /// <summary>Widest <see cref="PoseLimitDegrees"/> (MOCAP_POSE_LIMITS_MAX_DEG).</summary>
        public const float MaxPoseLimitDegrees = 90.0f;
        /// <summary>Pose limits: with a tolerance &gt; 0 (degrees) a joint the model bends where no
        /// person's joint goes (further than this from every rotation that joint takes in the
        /// training people's motion capture) is turned back to that distance before anything
        /// else reads the pose; poses within the range pass unchanged. 25 keeps joints out of what
        /// the project's evaluations count as broken. 0 (the default) leaves the pose as the
        /// model gave it.</summary>
        public float PoseLimitDegrees { get; set; }
        /// <summary>Chest following, for a model that reads a chest sensor: with a share &gt; 0 (up
        /// to 1) the spine turns that share of the way from where the model put the chest to
        /// where the chest sensor reports it, spread over the lower back as people bend it; the
        /// head and the upper arms keep the model's orientation. 0.5 takes the seven-sensor
        /// model's joint positions from 5.2 to 4.6 cm on people it never saw. No effect without a chest sensor;
        /// 0 (the default) leaves the pose as the model gave it.</summary>
        public float ChestFollowShare { get; set; }

        /// <summary>A tolerance the engine takes from any slider value: 0 or less turns the limits
        /// off, anything else is held to <see cref="MinPoseLimitDegrees"/> ..
        /// <see cref="MaxPoseLimitDegrees"/>.</summary>
        public static float PoseLimitFrom(float degrees)
        {
            if (!(degrees > 0f)) return 0f;
            return degrees < MinPoseLimitDegrees ? MinPoseLimitDegrees
                : degrees > MaxPoseLimitDegrees ? MaxPoseLimitDegrees : degrees;
        }

        /// <summary>A share the engine takes from any slider value: 0 or less (or not a number)
        /// turns chest following off, more than 1 is held to 1.</summary>
        public static float ChestFollowFrom(float share) => !(share > 0f) ? 0f : share > 1f ? 1f : share;

        internal unsafe void ToNative(out NativeSolverConfig native)
        {
            native = default;
            native.StructSize = (uint)sizeof(NativeSolverConfig);
            native.ContactThreshold = ContactThreshold;
            native.FloorHeight = FloorHeight;
            native.DriftCorrection = DriftCorrection ? 1 : 0;
            native.RequireCalibration = RequireCalibration ? 1 : 0;
            native.SmoothingMinCutoffHz = SmoothingMinCutoffHz;
            native.SmoothingBeta = SmoothingBeta;
        }
    }

    /// <summary>
    /// Runs a <see cref="MocapModel"/> for several characters, each fed by one
    /// <see cref="MocapSession"/>, on the engine's inference thread (one batched inference per
    /// tick), and hands out solved poses with root motion and contact-based drift correction.
    /// </summary>
    /// <remarks>
    /// <para>Lifecycle: <see cref="Open"/>, <see cref="AddCharacter"/> for each session (before
    /// <see cref="Start"/>; open each session with <see cref="SessionConfig.OutputRateHz"/> equal to
    /// <see cref="ModelInfo.FrameRate"/>), <see cref="Start"/>, start the sessions (before or after),
    /// then poll or drain poses per character. <see cref="Dispose"/> the solver first: the session
    /// handles and the model handle are referenced by the solver's handle and close only after it,
    /// so disposing them earlier is safe but defers their release.</para>
    /// <para>A session added here belongs to the solver: polling or draining its frames, or
    /// stopping it, throws until the solver is disposed.</para>
    /// <para>Threads: poll and drain from one thread. Allocation: <see cref="PollLatest"/> and
    /// <see cref="Drain"/> allocate nothing; exceptions do.</para>
    /// </remarks>
    public sealed class MocapSolver : IDisposable
    {
        /// <summary>Most characters one solver takes (MOCAP_MAX_CHARACTERS).</summary>
        public const int MaxCharacters = NativeSolverMethods.MaxCharacters;

        readonly SolverHandle _handle;
        readonly List<MocapSession> _sessions = new List<MocapSession>();
        // Per character: a poll or drain reported the end of its replay.
        readonly bool[] _ended = new bool[MaxCharacters];
        bool _started;
        bool _disposed;

        MocapSolver(MocapModel model, SolverHandle handle)
        {
            Model = model;
            _handle = handle;
            // The sessions are handed back only once mocap_solver_close has stopped the inference
            // thread: Dispose only defers that close while another thread is inside a solver call
            // (ResetCharacter, GetStats), and a session polled meanwhile would have two consumers.
            handle.Closed = ReleaseSessions;
        }

        void ReleaseSessions()
        {
            foreach (var session in _sessions)
                if (session.ConsumingSolver == this) session.ConsumingSolver = null;
        }

        /// <summary>Create a solver for a model (its config defaults when <paramref name="config"/> is null).</summary>
        /// <exception cref="MocapException">The engine refused the config; its text says why.</exception>
        public static unsafe MocapSolver Open(MocapModel model, SolverConfig config = null)
        {
            if (model == null) throw new ArgumentNullException(nameof(model));
            (config ?? new SolverConfig()).ToNative(out var native);
            var modelHandle = model.Handle;
            var handle = new SolverHandle();
            // The reference comes first so the model cannot close between open and adoption.
            handle.AddDependency(modelHandle);
            IntPtr solver;
            var status = NativeSolverMethods.mocap_solver_open(modelHandle, &native, out solver);
            if (status != MocapStatus.Ok)
            {
                var failure = NativeMethods.Failure(status);
                handle.RemoveLastDependency();
                handle.Dispose();
                throw failure;
            }
            handle.Adopt(solver);
            var delay = config?.SmoothingDelayFrames ?? 0;
            if (delay != 0)
                status = NativeSolverMethods.mocap_solver_set_smoothing_delay(handle, delay);
            var slide = config?.FootPinSlideSpeed ?? 0f;
            if (status == MocapStatus.Ok && slide != 0f)
                status = NativeSolverMethods.mocap_solver_set_foot_pinning(handle, slide);
            var limit = config?.PoseLimitDegrees ?? 0f;
            if (status == MocapStatus.Ok && limit != 0f)
                status = NativeSolverMethods.mocap_solver_set_pose_limits(handle, limit);
            var chest = config?.ChestFollowShare ?? 0f;
            if (status == MocapStatus.Ok && chest != 0f)
                status = NativeSolverMethods.mocap_solver_set_chest_follow(handle, chest);
            if (status != MocapStatus.Ok)
            {
                var failure = NativeMethods.Failure(status);
                handle.Dispose();
                throw failure;
            }
            return new MocapSolver(model, handle);
        }

        /// <summary>The model this solver runs.</summary>
        public MocapModel Model { get; }

        /// <summary>Characters added so far.</summary>
        public int CharacterCount => _sessions.Count;

        /// <summary>The inference thread is running.</summary>
        public bool IsStarted => _started;

        /// <summary>The session feeding a character.</summary>
        public MocapSession GetSession(int character)
        {
            CheckCharacter(character);
            return _sessions[character];
        }

        /// <summary>A poll or drain has reported that the character's replay is finished.</summary>
        public bool IsEndOfStream(int character)
        {
            CheckCharacter(character);
            return _ended[character];
        }

        /// <summary>
        /// Add a character fed by <paramref name="session"/> (open, not yet consumed by another
        /// solver). Returns its index: 0, 1, ...
        /// </summary>
        /// <exception cref="MocapException">The engine refused: started already, too many
        /// characters, or the session's output rate differs from the model's frame rate.</exception>
        public unsafe int AddCharacter(MocapSession session)
        {
            if (session == null) throw new ArgumentNullException(nameof(session));
            var handle = Handle;
            if (session.ConsumingSolver != null && session.ConsumingSolver != this)
                throw new InvalidOperationException("the session already feeds another MocapSolver");
            var sessionHandle = session.NativeHandle;
            _handle.AddDependency(sessionHandle);
            int character = -1;
            var status = NativeSolverMethods.mocap_solver_add_character(handle, sessionHandle, &character);
            if (status != MocapStatus.Ok)
            {
                var failure = NativeMethods.Failure(status);
                _handle.RemoveLastDependency();
                throw failure;
            }
            session.ConsumingSolver = this;
            _sessions.Add(session);
            return character;
        }

        /// <summary>Start the inference thread (start the sessions yourself, before or after).</summary>
        public void Start()
        {
            NativeMethods.Check(NativeSolverMethods.mocap_solver_start(Handle));
            _started = true;
        }

        /// <summary>
        /// Copy the character's newest pose into <paramref name="pose"/>, skipping older ones.
        /// <see cref="MocapPollResult.NoData"/>: nothing new (pose left as it was);
        /// <see cref="MocapPollResult.EndOfStream"/>: its replay is finished and every pose was
        /// taken. Allocates nothing.
        /// </summary>
        public unsafe MocapPollResult PollLatest(int character, ref MocapPose pose)
        {
            MocapStatus status;
            // The engine writes only on success, so a NoData poll leaves the caller's pose intact.
            fixed (MocapPose* p = &pose)
                status = NativeSolverMethods.mocap_solver_poll_latest(Handle, character, p);
            return Result(character, status);
        }

        /// <summary>
        /// For a consumer that drains every pose but shows the newest: after a pause longer than
        /// the engine keeps (1024 poses, about 17 s at 60 Hz: an editor paused, a breakpoint)
        /// the poses beyond those were dropped, and the newest one <see cref="Drain"/> returns is
        /// as old as the pause. When poses were dropped since <paramref name="droppedSeen"/>
        /// (the character's <see cref="MocapSolverStats.PosesDropped"/> at the previous call,
        /// updated here), this polls the newest pose into <paramref name="pose"/>; otherwise it
        /// returns <see cref="MocapPollResult.NoData"/> and takes nothing, so drained poses stay
        /// complete in normal running. Call it after draining. Allocates nothing.
        /// </summary>
        public MocapPollResult CatchUp(int character, ref ulong droppedSeen, ref MocapPose pose)
        {
            ulong dropped = GetStats(character).PosesDropped;
            if (dropped == droppedSeen) return MocapPollResult.NoData;
            droppedSeen = dropped;
            return PollLatest(character, ref pose);
        }

        /// <summary>
        /// Copy the character's poses solved since the previous drain, oldest first, into
        /// <paramref name="destination"/> (up to its length); <paramref name="count"/> receives how
        /// many. Poses that do not fit stay queued. Allocates nothing.
        /// </summary>
        public unsafe MocapPollResult Drain(int character, Span<MocapPose> destination, out int count)
        {
            count = 0;
            if (destination.Length == 0)
                throw new ArgumentException("the destination holds no poses", nameof(destination));
            uint n = 0;
            MocapStatus status;
            fixed (MocapPose* poses = destination)
                status = NativeSolverMethods.mocap_solver_drain(Handle, character, poses,
                                                                (uint)destination.Length, &n);
            count = (int)n;
            return Result(character, status);
        }

        /// <summary>
        /// Clear a character's recurrent state and root motion (e.g. after a new calibration);
        /// takes effect before its next frame. Any thread.
        /// </summary>
        public void ResetCharacter(int character)
        {
            NativeMethods.Check(NativeSolverMethods.mocap_solver_reset_character(Handle, character));
        }

        /// <summary>
        /// The performer's standing height in metres (<see cref="MinHeight"/> to
        /// <see cref="MaxHeight"/>), or 0 for the model's own training height (the default).
        /// The pose keeps the model's skeleton; the root moves as far for that skeleton as the
        /// performer did for their body, so a tall performer's strides no longer slide the feet.
        /// Needs a model with <see cref="ModelInfo.HasStrideScaling"/>. Any thread; takes effect
        /// from the character's next frame.
        /// </summary>
        /// <exception cref="MocapException">A height out of range (InvalidArgument) or a model
        /// without stride scaling (Unsupported), with the engine's reason.</exception>
        public void SetCharacterHeight(int character, float heightMeters)
        {
            NativeMethods.Check(NativeSolverMethods.mocap_solver_set_character_height(Handle, character, heightMeters));
        }

        /// <summary>MOCAP_HEIGHT_MIN_M: the shortest performer height accepted, metres.</summary>
        public const float MinHeight = 1.0f;

        /// <summary>MOCAP_HEIGHT_MAX_M: the tallest performer height accepted, metres.</summary>
        public const float MaxHeight = 2.5f;

        /// <summary>
        /// Counters and health of the solver: over all characters (<paramref name="character"/>
        /// -1) or one character's frame counters (ticks, timings and failure texts are
        /// solver-wide). A failed inference is only visible here (it happens on the engine's
        /// thread): check <see cref="MocapSolverStats.RunFailures"/>. Allocates nothing.
        /// </summary>
        public unsafe MocapSolverStats GetStats(int character = -1)
        {
            MocapSolverStats stats;
            NativeMethods.Check(NativeSolverMethods.mocap_solver_get_stats(Handle, character, &stats));
            return stats;
        }

        /// <summary>
        /// One solver counter by key (<paramref name="character"/> -1: the totals), as
        /// <see cref="GetStats"/> reports it. Throws <see cref="MocapException"/> (Unsupported) for a
        /// key the loaded library does not know. Allocates nothing.
        /// </summary>
        public unsafe ulong GetCounter(SolverCounter counter, int character = -1)
        {
            ulong value;
            NativeMethods.Check(NativeSolverMethods.mocap_solver_get_counter(Handle, character, (int)counter, &value));
            return value;
        }

        /// <summary>
        /// Stop the inference thread and free the solver. The sessions and the model stay open
        /// (their owners dispose them) and the sessions may be polled directly again.
        /// </summary>
        public void Dispose()
        {
            if (_disposed) return;
            _disposed = true;
            _handle.Dispose();   // the sessions come back in SolverHandle.ReleaseHandle (ReleaseSessions)
            _started = false;
        }

        /// <summary>The native handle, whatever its state (tests).</summary>
        internal SolverHandle NativeHandle => _handle;

        SolverHandle Handle
        {
            get
            {
                if (_disposed) throw new ObjectDisposedException(nameof(MocapSolver));
                return _handle;
            }
        }

        MocapPollResult Result(int character, MocapStatus status)
        {
            if (status == MocapStatus.Ok) return MocapPollResult.Frames;
            if (status == MocapStatus.NoData) return MocapPollResult.NoData;
            if (status == MocapStatus.EndOfStream)
            {
                _ended[character] = true;
                return MocapPollResult.EndOfStream;
            }
            // Unknown characters are reported by the engine (its text names the index).
            throw NativeMethods.Failure(status);
        }

        void CheckCharacter(int character)
        {
            if ((uint)character >= (uint)_sessions.Count)
                throw new ArgumentOutOfRangeException(nameof(character), character,
                    $"{_sessions.Count} character(s) added");
        }
    }
}
