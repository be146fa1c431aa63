using System;
using System.IO;
using System.Text;
using System.Threading.Tasks;
using Mocap.Imu.Capture;
using Mocap.Imu.Recording;

namespace Mocap.Imu
{
    /// <summary>Where a <see cref="MocapRunner"/> (and the session component around it) is.</summary>
    public enum MocapComponentStatus
    {
        /// <summary>Nothing open.</summary>
        Idle = 0,
        /// <summary>Loading the model and opening the sources on a worker thread.</summary>
        Opening = 1,
        /// <summary>Sessions and solver running; poses arrive.</summary>
        Running = 2,
        /// <summary>Every playback reached its end.</summary>
        Ended = 3,
        /// <summary>Opening or running failed; <see cref="MocapRunner.LastError"/> says why.</summary>
        Failed = 4,
    }

    /// <summary>A replay's own calibration windows, seconds after its first record.</summary>
    public readonly struct PlaybackCalibrationWindows
    {
        public readonly float HeadingStart, HeadingSeconds, TPoseStart, TPoseSeconds;

        public PlaybackCalibrationWindows(float headingStart, float headingSeconds, float tposeStart, float tposeSeconds)
        {
            HeadingStart = headingStart;
            HeadingSeconds = headingSeconds;
            TPoseStart = tposeStart;
            TPoseSeconds = tposeSeconds;
        }
    }

    /// <summary>One character of a <see cref="MocapRunPlan"/>.</summary>
    public sealed class MocapRunCharacter
    {
        /// <summary>Shown in status text and used in recording file names.</summary>
        public string Name = "Performer";
        /// <summary>The session to open (its capture path is set by the runner while recording).</summary>
        public SessionConfig Config;
        /// <summary>A calibration file to load when no calibration is carried over (null: none).</summary>
        public string CalibrationFile;
        /// <summary>Replay: the capture's own calibration windows, scheduled when nothing else calibrates it.</summary>
        public PlaybackCalibrationWindows? PlaybackWindows;
        /// <summary>The performer's standing height, metres (0: the model's training height);
        /// see <see cref="MocapSolver.SetCharacterHeight"/>.</summary>
        public float HeightMeters;
    }

    /// <summary>What a <see cref="MocapRunner"/> opens: read from the settings on the main thread.</summary>
    public sealed class MocapRunPlan
    {
        public string ModelPath;
        public ModelOptions ModelOptions;
        public SolverConfig SolverConfig;
        public MocapRunCharacter[] Characters = Array.Empty<MocapRunCharacter>();
        /// <summary>Record every character's raw bytes into new files in this folder (null: no recording).</summary>
        public string RecordingFolder;
    }

    /// <summary>What one <see cref="MocapRunner.Update"/> brought about.</summary>
    public enum MocapRunnerEvent
    {
        None = 0,
        /// <summary>The engine opened and runs (raise "opened" listeners now).</summary>
        Opened = 1,
        /// <summary>Every playback reached its end (loop by restarting, or stay ended).</summary>
        Ended = 2,
        /// <summary>Opening or running failed; everything is closed; see <see cref="MocapRunner.LastError"/>.</summary>
        Failed = 3,
    }

    /// <summary>
    /// The engine's lifecycle for several characters, without Unity: loads the model and opens one
    /// session per character and one solver on a worker thread (the caller's thread never
    /// blocks), drains every character's poses into preallocated buffers on each
    /// <see cref="Update"/> (no per-frame allocation), records raw captures, carries calibrations
    /// across restarts, and builds the status text. The session component is its inspector shell.
    /// </summary>
    /// <remarks>
    /// Close order: solver, sessions, model, as the engine requires. Every method and event runs on
    /// the caller's thread; the engine never calls managed code from its own threads.
    /// </remarks>
    public sealed class MocapRunner : IDisposable
    {
        /// <summary>Receives one solved pose of a character.</summary>
        public delegate void PoseHandler(int character, in MocapPose pose);

        const int DrainCapacity = 32;
        // Enough rounds to empty the engine's whole queue (1024 poses) in one update after a pause.
        const int MaxDrainRounds = 1024 / DrainCapacity + 2;

        // Everything opened by one worker-thread open; disposed as a unit, in the right order.
        sealed class Engine : IDisposable
        {
            public MocapModel Model;
            public MocapSolver Solver;
            public MocapSession[] Sessions;
            // Each character's calibration as its session stopped (null: none, or it failed to
            // stop): read after the stop, which still finishes a step on the bytes read before it.
            public CalibrationData?[] FinalCalibrations;

            public void Dispose() => Shutdown();

            // Closes everything; returns why a character's recording failed (its capture is
            // incomplete), "" when none did. The last flush and close happen here, so a disk
            // that filled at the end is only known now.
            public string Shutdown()
            {
                Solver?.Dispose();
                string failures = "";
                if (Sessions != null)
                {
                    FinalCalibrations = new CalibrationData?[Sessions.Length];
                    for (int c = 0; c < Sessions.Length; c++)
                    {
                        var session = Sessions[c];
                        if (session == null) continue;
                        try
                        {
                            var stats = session.Stop();
                            FinalCalibrations[c] = session.Calibration;
                            if (stats.CaptureError != MocapStatus.Ok)
                                failures += $"recording of character {c} failed ({stats.CaptureError}): {stats.LastError}\n";
                        }
                        catch (Exception e) when (e is MocapException || e is InvalidOperationException)
                        {
                            failures += $"character {c} did not stop cleanly: {e.Message}\n";
                        }
                        session.Dispose();
                    }
                }
                Model?.Dispose();
                Solver = null;
                Sessions = null;
                Model = null;
                return failures.TrimEnd('\n');
            }
        }

        sealed class OpenRequest
        {
            public MocapRunPlan Plan;
            public SessionConfig[] Configs;
            public CalibrationData?[] Calibrations;
        }

        Engine _engine;
        Task<Engine> _opening;
        // The characters' names from the plan last opened.
        string[] _names = Array.Empty<string>();
        // An open that Close() gave up on: it disposes what it opened once done. The next open
        // waits for it, since it holds the same serial ports and files until then.
        Task _abandoned;
        string[] _recordingPaths = Array.Empty<string>();

        // Per character, allocated once per open with a new character count.
        MocapPose[] _latest = Array.Empty<MocapPose>();
        bool[] _hasPose = Array.Empty<bool>();
        ulong[] _poseCount = Array.Empty<ulong>();
        ulong[] _posesDroppedSeen = Array.Empty<ulong>();
        readonly MocapPose[] _drain = new MocapPose[DrainCapacity];
        readonly StringBuilder _statusBuilder = new StringBuilder(512);

        /// <summary>Where the runner is.</summary>
        public MocapComponentStatus Status { get; private set; }

        /// <summary>The last error, "" when none.</summary>
        public string LastError { get; private set; } = "";

        /// <summary>Characters opened (0 until <see cref="Status"/> is Running).</summary>
        public int CharacterCount => _engine?.Sessions?.Length ?? 0;

        /// <summary>The loaded model (null until running): skeleton, frame rate.</summary>
        public MocapModel Model => _engine?.Model;

        /// <summary>Whether raw captures are being recorded by the running engine.</summary>
        public bool IsRecording => _engine != null && Array.Exists(_recordingPaths, p => !string.IsNullOrEmpty(p));

        /// <summary>Raised for every pose drained (oldest first), during <see cref="Update"/>.</summary>
        public event PoseHandler PoseSolved;

        /// <summary>Raised before the engine closes (listeners still see the sessions).</summary>
        public event Action Closing;

        /// <summary>Raised with each error as it is reported (failures and recordings that failed).</summary>
        public event Action<string> ErrorReported;

        /// <summary>Receives exceptions thrown by listeners, which never stop the capture.</summary>
        public Action<Exception> ListenerFailed;

        /// <summary>The capture file each character records to (empty when not recording).</summary>
        public string GetRecordingPath(int character) =>
            character >= 0 && character < _recordingPaths.Length ? _recordingPaths[character] ?? "" : "";

        /// <summary>The character's name from the plan.</summary>
        public string GetCharacterName(int character)
        {
            return character >= 0 && character < _names.Length ? _names[character] : $"#{character}";
        }

        /// <summary>
        /// Start opening <paramref name="plan"/> on a worker thread. False (and nothing changes)
        /// while opening or running; false with <see cref="Status"/> Failed when the plan is unusable.
        /// </summary>
        public bool Open(MocapRunPlan plan) => Open(plan, null, null);

        // carriedFrom/carry: the configs and calibrations of the sessions a restart closed.
        bool Open(MocapRunPlan plan, SessionConfig[] carriedFrom, CalibrationData?[] carry)
        {
            if (_opening != null || _engine != null) return false;
            if (plan?.Characters == null || plan.Characters.Length == 0)
            {
                Fail("no character to open: the settings need at least one");
                return false;
            }
            OpenRequest request;
            try
            {
                int n = plan.Characters.Length;
                var capturePaths = new string[n];
                if (!string.IsNullOrEmpty(plan.RecordingFolder))
                {
                    Directory.CreateDirectory(plan.RecordingFolder);
                    // Never an existing name: the capture writer truncates the file it opens.
                    var now = DateTime.Now;
                    var previous = _recordingPaths;
                    for (int c = 0; c < n; c++)
                        capturePaths[c] = TakeNaming.CapturePath(plan.RecordingFolder, now, c, plan.Characters[c].Name,
                            p => File.Exists(p) || Array.IndexOf(previous, p) >= 0 || Array.IndexOf(capturePaths, p) >= 0);
                }
                request = new OpenRequest { Plan = plan, Configs = new SessionConfig[n] };
                for (int c = 0; c < n; c++)
                {
                    var config = plan.Characters[c].Config ?? throw new ArgumentException($"character {c} has no session config");
                    config = config.Clone();
                    config.CapturePath = capturePaths[c] ?? string.Empty;
                    request.Configs[c] = config;
                }
                // Only to the same characters' same sensors (the list may have changed meanwhile).
                request.Calibrations = CalibrationCarry.Match(carriedFrom, carry, request.Configs);
                for (int c = 0; c < n; c++)
                    if (request.Calibrations[c] == null && !string.IsNullOrEmpty(plan.Characters[c].CalibrationFile))
                        request.Calibrations[c] = CalibrationData.Load(plan.Characters[c].CalibrationFile);
                _recordingPaths = capturePaths;
                _names = Array.ConvertAll(plan.Characters, ch => ch.Name ?? "");
            }
            catch (Exception e)
            {
                Fail(e.Message);
                return false;
            }
            SetStatus(MocapComponentStatus.Opening);
            var waitFor = _abandoned;
            _abandoned = null;
            _opening = waitFor != null && !waitFor.IsCompleted
                ? waitFor.ContinueWith(_ => OpenEngine(request), TaskScheduler.Default)
                : Task.Run(() => OpenEngine(request));
            return true;
        }

        // Worker thread.
        static Engine OpenEngine(OpenRequest r)
        {
            var engine = new Engine();
            try
            {
                engine.Model = MocapModel.Open(r.Plan.ModelPath, r.Plan.ModelOptions);
                float rate = engine.Model.Info.FrameRate;
                engine.Sessions = new MocapSession[r.Configs.Length];
                for (int c = 0; c < r.Configs.Length; c++)
                {
                    var config = r.Configs[c];
                    config.OutputRateHz = rate; // sessions feeding the model run at its rate
                    // A sensor the model can do without must not block calibration when absent.
                    config.MarkModelOptionalSensors(engine.Model.Info);
                    var session = MocapSession.Open(config);
                    engine.Sessions[c] = session;
                    if (r.Calibrations[c] is CalibrationData calibration)
                    {
                        session.Calibration = calibration;
                    }
                    else if (config.Source == MocapSourceKind.Replay && r.Plan.Characters[c].PlaybackWindows is PlaybackCalibrationWindows w)
                    {
                        double t0 = FirstReceiveSeconds(config.Path);
                        session.ScheduleCalibration(CalibrationStep.Heading, t0 + w.HeadingStart, w.HeadingSeconds);
                        session.ScheduleCalibration(CalibrationStep.TPose, t0 + w.TPoseStart, w.TPoseSeconds);
                    }
                }
                engine.Solver = MocapSolver.Open(engine.Model, r.Plan.SolverConfig);
                for (int c = 0; c < engine.Sessions.Length; c++)
                {
                    int character = engine.Solver.AddCharacter(engine.Sessions[c]);
                    float height = r.Plan.Characters[c].HeightMeters;
                    try
                    {
                        engine.Solver.SetCharacterHeight(character, height);
                    }
                    catch (MocapException e)
                    {
                        throw new MocapException(e.Status, $"character '{r.Plan.Characters[c].Name}': performer height {height:0.###} m: {e.Message}", e);
                    }
                }
                engine.Solver.Start();
                foreach (var session in engine.Sessions) session.Start();
                return engine;
            }
            catch
            {
                engine.Dispose();
                throw;
            }
        }

        static double FirstReceiveSeconds(string capture)
        {
            using var reader = new CaptureReader(capture);
            if (!reader.TryReadNext(out var record))
                throw new MocapException(MocapStatus.Format, $"{capture}: the capture holds no records");
            return record.ReceiveNs * 1e-9;
        }

        /// <summary>
        /// Close everything (solver, sessions, model); safe at any time. Returns why a recording
        /// failed at its end ("" when none did), which is also reported through <see cref="ErrorReported"/>.
        /// </summary>
        public string Close()
        {
            if (_opening != null)
            {
                // Still opening: whatever it opens is closed on the worker once it is done.
                _abandoned = _opening.ContinueWith(t => { if (t.Status == TaskStatus.RanToCompletion) t.Result.Dispose(); },
                                                   TaskScheduler.Default);
                _opening = null;
            }
            string recordingFailure = "";
            if (_engine != null)
            {
                try { Closing?.Invoke(); }
                catch (Exception e) { ListenerFailed?.Invoke(e); }
                recordingFailure = _engine.Shutdown();
                _engine = null;
            }
            if (Status == MocapComponentStatus.Running || Status == MocapComponentStatus.Opening || Status == MocapComponentStatus.Ended)
                SetStatus(MocapComponentStatus.Idle);
            if (recordingFailure.Length > 0)
            {
                // After a failure (the reason it closed) both messages matter.
                LastError = Status == MocapComponentStatus.Failed && LastError.Length > 0
                    ? LastError + "\n" + recordingFailure
                    : recordingFailure;
                Report(recordingFailure);
            }
            return recordingFailure;
        }

        /// <summary>
        /// Close and open <paramref name="plan"/>, keeping each character's calibration when the
        /// characters and their sensors are the same as before.
        /// </summary>
        public bool Restart(MocapRunPlan plan)
        {
            SessionConfig[] carriedFrom = null;
            var engine = _engine;
            if (engine != null)
            {
                carriedFrom = new SessionConfig[engine.Sessions.Length];
                for (int c = 0; c < carriedFrom.Length; c++) carriedFrom[c] = engine.Sessions[c].Config;
            }
            Close();
            CalibrationData?[] carry = null;
            if (engine?.FinalCalibrations != null)
            {
                // Taken after each session stopped, so a step that finished on the last bytes is carried too.
                carry = new CalibrationData?[engine.FinalCalibrations.Length];
                for (int c = 0; c < carry.Length; c++)
                {
                    var calibration = engine.FinalCalibrations[c];
                    if (calibration.HasValue && (calibration.Value.ValidMask | calibration.Value.HeadingMask) != 0)
                        carry[c] = calibration;
                }
            }
            return Open(plan, carriedFrom, carry);
        }

        /// <summary>
        /// Adopt a finished open and drain every character's poses (raising <see cref="PoseSolved"/>).
        /// Call once per rendered frame. Allocates nothing while running.
        /// </summary>
        public MocapRunnerEvent Update()
        {
            if (_opening != null && _opening.IsCompleted) return AdoptOpened();
            if (_engine == null || Status != MocapComponentStatus.Running) return MocapRunnerEvent.None;
            try
            {
                bool allEnded = true;
                var solver = _engine.Solver;
                for (int c = 0; c < _latest.Length; c++)
                {
                    if (solver.IsEndOfStream(c)) continue;
                    allEnded = false;
                    // Drain everything solved since the last update, keep the newest.
                    for (int round = 0; round < MaxDrainRounds; round++)
                    {
                        var result = solver.Drain(c, _drain, out int count);
                        if (count > 0)
                        {
                            _latest[c] = _drain[count - 1];
                            _hasPose[c] = true;
                            _poseCount[c] += (ulong)count;
                            if (PoseSolved != null) RaisePoseSolved(c, count);
                        }
                        if (result != MocapPollResult.Frames || count < DrainCapacity) break;
                    }
                    // After a pause longer than the engine's queue the drained poses are old.
                    if (solver.CatchUp(c, ref _posesDroppedSeen[c], ref _latest[c]) == MocapPollResult.Frames)
                    {
                        _hasPose[c] = true;
                        _poseCount[c]++;
                        _drain[0] = _latest[c];
                        if (PoseSolved != null) RaisePoseSolved(c, 1);
                    }
                }
                if (allEnded)
                {
                    SetStatus(MocapComponentStatus.Ended);
                    return MocapRunnerEvent.Ended;
                }
                return MocapRunnerEvent.None;
            }
            catch (Exception e)
            {
                Fail(e.Message);
                Close();
                Status = MocapComponentStatus.Failed;
                return MocapRunnerEvent.Failed;
            }
        }

        void RaisePoseSolved(int character, int count)
        {
            for (int i = 0; i < count; i++)
            {
                // A failing listener must not stop the capture (or the other listeners' frames).
                try { PoseSolved?.Invoke(character, in _drain[i]); }
                catch (Exception e) { ListenerFailed?.Invoke(e); }
            }
        }

        MocapRunnerEvent AdoptOpened()
        {
            var task = _opening;
            _opening = null;
            if (task.Status != TaskStatus.RanToCompletion)
            {
                var e = task.Exception?.GetBaseException();
                _recordingPaths = Array.Empty<string>();
                Fail(e?.Message ?? "opening was cancelled");
                return MocapRunnerEvent.Failed;
            }
            _engine = task.Result;
            int n = _engine.Sessions.Length;
            if (_latest.Length != n)
            {
                _latest = new MocapPose[n];
                _hasPose = new bool[n];
                _poseCount = new ulong[n];
                _posesDroppedSeen = new ulong[n];
            }
            Array.Clear(_hasPose, 0, n);
            Array.Clear(_poseCount, 0, n);
            Array.Clear(_posesDroppedSeen, 0, n); // a new engine counts from zero
            SetStatus(MocapComponentStatus.Running);
            return MocapRunnerEvent.Opened;
        }

        /// <summary>
        /// The character's newest pose (model frame), or false before its first pose. Valid until
        /// the next <see cref="Update"/>. Allocates nothing.
        /// </summary>
        public bool TryGetLatestPose(int character, out MocapPose pose)
        {
            if (character >= 0 && character < _hasPose.Length && _hasPose[character])
            {
                pose = _latest[character];
                return true;
            }
            pose = default;
            return false;
        }

        /// <summary>Poses received for a character since the engine opened.</summary>
        public ulong GetPoseCount(int character) =>
            character >= 0 && character < _poseCount.Length ? _poseCount[character] : 0;

        /// <summary>The character's session (for stats and calibration), or null when not running.</summary>
        public MocapSession GetSession(int character) =>
            _engine != null && character >= 0 && character < _engine.Sessions.Length ? _engine.Sessions[character] : null;

        /// <summary>Start a calibration step on a character (any time while running).</summary>
        public void BeginCalibration(int character, CalibrationStep step, float seconds)
        {
            var session = GetSession(character) ?? throw new InvalidOperationException("the session is not running");
            session.BeginCalibration(step, seconds);
        }

        /// <summary>The latest report of a step for a character (default when not running). Allocates nothing.</summary>
        public CalibrationReport GetCalibrationReport(int character, CalibrationStep step)
        {
            var session = GetSession(character);
            return session != null ? session.GetCalibrationReport(step) : default;
        }

        /// <summary>Clear a character's recurrent state and root motion (after a new calibration).</summary>
        public void ResetCharacter(int character) => _engine?.Solver?.ResetCharacter(character);

        /// <summary>
        /// Change a running character's performer height (metres, 0: the model's training height),
        /// e.g. from a menu where a player enters it; from their next frame.
        /// </summary>
        /// <exception cref="InvalidOperationException">Not running.</exception>
        /// <exception cref="MocapException">Out of range, or a model without stride scaling.</exception>
        public void SetCharacterHeight(int character, float heightMeters)
        {
            var solver = _engine?.Solver ?? throw new InvalidOperationException("the session is not running");
            solver.SetCharacterHeight(character, heightMeters);
        }

        /// <summary>Save a character's calibration (load it later as a character's calibration file).</summary>
        public void SaveCalibration(int character, string path)
        {
            var session = GetSession(character) ?? throw new InvalidOperationException("the session is not running");
            session.Calibration.Save(path);
        }

        /// <summary>
        /// Per character: connection, poses, calibration, sensors seen, recording size, errors,
        /// replay damage and inference failures. One string per call (callers refresh it a few
        /// times a second, not per frame).
        /// </summary>
        public string BuildStatusText()
        {
            var text = _statusBuilder.Clear();
            for (int c = 0; c < CharacterCount; c++)
            {
                var session = _engine.Sessions[c];
                var stats = session.GetStats();
                var calibration = session.Calibration;
                text.Append(GetCharacterName(c)).Append(": ").Append(stats.ConnectionState)
                    .Append(", ").Append(_poseCount[c]).Append(" poses, ")
                    .Append(calibration.IsComplete ? "calibrated" : "not calibrated")
                    .Append(", sensors seen 0x").Append(stats.SensorsSeenMask.ToString("X2"));
                if (!string.IsNullOrEmpty(GetRecordingPath(c)))
                    text.Append(", recording ").Append(stats.CaptureBytesWritten / 1024).Append(" KiB");
                var error = stats.LastError;
                if (!string.IsNullOrEmpty(error)) text.Append("\n  ").Append(error);
                // A replay passes over damage silently; the poses then miss part of the capture.
                if (stats.ReplayChunksSkipped > 0 || stats.ReplayTailDamaged)
                    text.Append("\n  ").Append(stats.ReplayDamage);
                // Inference runs on the engine's thread: its failures are only visible here.
                var solved = _engine.Solver.GetStats(c);
                if (solved.RunFailures > 0)
                    text.Append("\n  inference failed for ").Append(solved.RunFailures).Append(" of ")
                        .Append(solved.FramesSolved).Append(" frames (poses held): ").Append(solved.LastRunError);
                text.Append('\n');
            }
            return text.ToString();
        }

        /// <summary>Closes everything; an open still running is closed on the worker when done.</summary>
        public void Dispose() => Close();

        /// <summary>Waits until an open that <see cref="Close"/> gave up on has closed what it opened.</summary>
        public bool WaitForAbandonedOpen(TimeSpan timeout) => _abandoned == null || _abandoned.Wait(timeout);

        void SetStatus(MocapComponentStatus value)
        {
            Status = value;
            if (value != MocapComponentStatus.Failed) LastError = "";
        }

        void Fail(string message)
        {
            Status = MocapComponentStatus.Failed;
            LastError = message ?? "";
            Report(LastError);
        }

        void Report(string message)
        {
            try { ErrorReported?.Invoke(message); }
            catch (Exception e) { ListenerFailed?.Invoke(e); }
        }
    }
}
