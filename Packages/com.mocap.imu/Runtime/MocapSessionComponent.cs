using System;
using System.IO;
using System.Threading.Tasks;
using Mocap.Imu.Capture;
using Mocap.Imu.Recording;
using UnityEngine;

namespace Mocap.Imu
{
    /// <summary>Where a <see cref="MocapSessionComponent"/> is.</summary>
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
        /// <summary>Opening or running failed; <see cref="MocapSessionComponent.LastError"/> says why.</summary>
        Failed = 4,
    }

    /// <summary>
    /// Runs the engine for the characters of a <see cref="MocapSettings"/>: loads the model, opens
    /// one session per character and one solver on a worker thread (nothing blocks the main
    /// thread), then drains every character's poses each Update into preallocated buffers
    /// (no per-frame allocation). Pose drivers, the overlay and the VMC streamer read from here.
    /// </summary>
    /// <remarks>
    /// Close order (OnDisable, OnDestroy, restart): solver first, then the sessions, then the
    /// model, as the engine requires. The engine never calls managed code from its threads.
    /// </remarks>
    [DefaultExecutionOrder(-100)]
    [DisallowMultipleComponent]
    [AddComponentMenu("Mocap IMU/Mocap Session")]
    public sealed class MocapSessionComponent : MonoBehaviour
    {
        const int DrainCapacity = 32;
        // Enough rounds to empty the engine's whole queue (1024 poses) in one frame after a pause.
        const int MaxDrainRounds = 1024 / DrainCapacity + 2;

        [Tooltip("Model, solver and one source per character.")]
        public MocapSettings settings;

        [Tooltip("Open the sessions when the component is enabled.")]
        public bool openOnEnable = true;

        [Tooltip("Playback: start again from the beginning when every capture has ended.")]
        public bool loopPlayback;

        [Header("Status (read only)")]
        [Tooltip("Idle, Opening, Running, Ended (every playback finished) or Failed (see Last Error).")]
        [SerializeField, ReadOnlyField] MocapComponentStatus status;
        [Tooltip("Per character: connection, poses solved, calibration, sensors seen, recording size, errors.")]
        [SerializeField, ReadOnlyField(8)] string statusText = "";
        [Tooltip("The last error the engine or the glue reported.")]
        [SerializeField, ReadOnlyField(4)] string lastError = "";

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
            public string ModelPath;
            public ModelOptions ModelOptions;
            public SolverConfig SolverConfig;
            public MocapCharacterSource[] Sources;
            public SessionConfig[] Configs;
            public string[] CapturePaths;
            public CalibrationData?[] Calibrations;
        }

        Engine _engine;
        Task<Engine> _opening;
        // An open that Close() gave up on: it disposes what it opened once done. The next open
        // waits for it, since it holds the same serial ports and files until then.
        Task _abandoned;
        bool _recording;
        string[] _recordingPaths = Array.Empty<string>();
        float _nextStatusText;

        // Per character, allocated once per open.
        MocapPose[] _latest = Array.Empty<MocapPose>();
        bool[] _hasPose = Array.Empty<bool>();
        ulong[] _poseCount = Array.Empty<ulong>();
        ulong[] _posesDroppedSeen = Array.Empty<ulong>();
        readonly MocapPose[] _drain = new MocapPose[DrainCapacity];

        /// <summary>Current status (also shown in the inspector).</summary>
        public MocapComponentStatus Status => status;

        /// <summary>The last error, "" when none.</summary>
        public string LastError => lastError;

        /// <summary>Human-readable status per character.</summary>
        public string StatusText => statusText;

        /// <summary>Characters opened (0 until <see cref="Status"/> is Running).</summary>
        public int CharacterCount => _engine?.Sessions?.Length ?? 0;

        /// <summary>The loaded model (null until running): skeleton, frame rate.</summary>
        public MocapModel Model => _engine?.Model;

        /// <summary>Whether raw captures are being recorded.</summary>
        public bool IsRecording => _recording && status == MocapComponentStatus.Running;

        /// <summary>The capture file each character records to while recording.</summary>
        public string GetRecordingPath(int character) =>
            character >= 0 && character < _recordingPaths.Length ? _recordingPaths[character] : string.Empty;

        /// <summary>Raised on the main thread once the engine runs (after each open or restart).</summary>
        public event Action<MocapSessionComponent> Opened;

        /// <summary>Receives one solved pose of a character.</summary>
        public delegate void PoseHandler(int character, in MocapPose pose);

        /// <summary>
        /// Raised on the main thread (from Update) for every pose drained, oldest first: also the
        /// poses solved between two rendered frames, which <see cref="TryGetLatestPose"/> skips.
        /// Recorders that must keep every frame of the model's rate listen here.
        /// </summary>
        public event PoseHandler PoseSolved;

        /// <summary>Raised on the main thread before the engine closes.</summary>
        public event Action<MocapSessionComponent> Closing;

        /// <summary>The character's display name from the settings.</summary>
        public string GetCharacterName(int character) =>
            settings != null && character >= 0 && character < settings.characters.Count ? settings.characters[character].name : $"#{character}";

        void OnEnable()
        {
            if (openOnEnable) Open();
        }

        void OnDisable() => Close();

        void OnDestroy() => Close();

        void OnApplicationQuit() => Close();

        /// <summary>Open everything on a worker thread (no-op while opening or running).</summary>
        public void Open() => Open(null, null);

        // carriedFrom/carry: the configs and calibrations of the sessions a restart closed.
        void Open(SessionConfig[] carriedFrom, CalibrationData?[] carry)
        {
            if (_opening != null || _engine != null) return;
            if (settings == null || settings.characters == null || settings.characters.Count == 0)
            {
                Fail("no MocapSettings with at least one character assigned");
                return;
            }
            OpenRequest request;
            try
            {
                // Unity objects and Application.* are read here, on the main thread.
                int n = settings.characters.Count;
                request = new OpenRequest
                {
                    ModelPath = settings.ResolveModelPath(),
                    ModelOptions = settings.ToModelOptions(),
                    SolverConfig = settings.ToSolverConfig(),
                    Sources = settings.characters.ToArray(),
                    CapturePaths = new string[n],
                };
                if (_recording)
                {
                    var folder = settings.ResolveRecordingFolder();
                    Directory.CreateDirectory(folder);
                    // Never an existing name: the capture writer truncates the file it opens.
                    var now = DateTime.Now;
                    var previousPaths = _recordingPaths;
                    for (int c = 0; c < n; c++)
                        request.CapturePaths[c] = TakeNaming.CapturePath(folder, now, c, request.Sources[c].name,
                            p => File.Exists(p) || Array.IndexOf(previousPaths, p) >= 0 || Array.IndexOf(request.CapturePaths, p) >= 0);
                }
                _recordingPaths = request.CapturePaths;
                request.Configs = new SessionConfig[n];
                for (int c = 0; c < n; c++)
                    request.Configs[c] = request.Sources[c].ToSessionConfig(0f, request.CapturePaths[c]);
                // Only to the same characters' same sensors (the list may have changed meanwhile).
                request.Calibrations = CalibrationCarry.Match(carriedFrom, carry, request.Configs);
                for (int c = 0; c < n; c++)
                    if (request.Calibrations[c] == null && !string.IsNullOrEmpty(request.Sources[c].calibrationFile))
                        request.Calibrations[c] = CalibrationData.Load(MocapSettings.ResolvePath(request.Sources[c].calibrationFile));
            }
            catch (Exception e)
            {
                Fail(e.Message);
                return;
            }
            SetStatus(MocapComponentStatus.Opening, "");
            var previous = _abandoned;
            _abandoned = null;
            _opening = previous != null && !previous.IsCompleted
                ? previous.ContinueWith(_ => OpenEngine(request), TaskScheduler.Default)
                : Task.Run(() => OpenEngine(request));
        }

        // Worker thread: no Unity API here.
        static Engine OpenEngine(OpenRequest r)
        {
            var engine = new Engine();
            try
            {
                engine.Model = MocapModel.Open(r.ModelPath, r.ModelOptions);
                float rate = engine.Model.Info.FrameRate;
                engine.Sessions = new MocapSession[r.Sources.Length];
                for (int c = 0; c < r.Sources.Length; c++)
                {
                    var source = r.Sources[c];
                    var config = r.Configs[c];
                    config.OutputRateHz = rate; // sessions feeding the model run at its rate
                    var session = MocapSession.Open(config);
                    engine.Sessions[c] = session;
                    if (r.Calibrations[c] is CalibrationData calibration)
                    {
                        session.Calibration = calibration;
                    }
                    else if (source.source == MocapSourceKind.Replay && source.playbackCalibrationWindows)
                    {
                        double t0 = FirstReceiveSeconds(config.Path);
                        session.ScheduleCalibration(CalibrationStep.Heading, t0 + source.playbackHeadingStart, source.playbackHeadingSeconds);
                        session.ScheduleCalibration(CalibrationStep.TPose, t0 + source.playbackTPoseStart, source.playbackTPoseSeconds);
                    }
                }
                engine.Solver = MocapSolver.Open(engine.Model, r.SolverConfig);
                foreach (var session in engine.Sessions) engine.Solver.AddCharacter(session);
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

        /// <summary>Close everything (solver, sessions, model). Safe to call at any time.</summary>
        public void Close()
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
                try { Closing?.Invoke(this); }
                catch (Exception e) { Debug.LogException(e, this); }
                recordingFailure = _engine.Shutdown();
                _engine = null;
            }
            if (status == MocapComponentStatus.Running || status == MocapComponentStatus.Opening || status == MocapComponentStatus.Ended)
                SetStatus(MocapComponentStatus.Idle, "");
            if (recordingFailure.Length > 0)
            {
                // After a failure (the reason it closed) both messages matter.
                lastError = status == MocapComponentStatus.Failed && lastError.Length > 0
                    ? lastError + "\n" + recordingFailure
                    : recordingFailure;
                Debug.LogError($"[Mocap IMU] {name}: {recordingFailure}", this);
            }
        }

        /// <summary>
        /// Close and open again, keeping each character's calibration (when the characters and
        /// their sensors are the same as before).
        /// </summary>
        public void Restart()
        {
            CalibrationData?[] carry = null;
            SessionConfig[] carriedFrom = null;
            var engine = _engine;
            if (engine != null)
            {
                carriedFrom = new SessionConfig[engine.Sessions.Length];
                for (int c = 0; c < carriedFrom.Length; c++) carriedFrom[c] = engine.Sessions[c].Config;
            }
            Close();
            if (engine?.FinalCalibrations != null)
            {
                // Taken after each session stopped (Engine.Shutdown), so a step that finished on
                // the last bytes is carried too.
                carry = new CalibrationData?[engine.FinalCalibrations.Length];
                for (int c = 0; c < carry.Length; c++)
                {
                    var calibration = engine.FinalCalibrations[c];
                    if (calibration.HasValue && (calibration.Value.ValidMask | calibration.Value.HeadingMask) != 0)
                        carry[c] = calibration;
                }
            }
            Open(carriedFrom, carry);
        }

        /// <summary>Record every character's raw sensor bytes (the engine's crash-safe capture format) from now on.</summary>
        public void StartRecording()
        {
            if (_recording) return;
            _recording = true;
            Restart();
        }

        /// <summary>Stop recording (the captures are flushed and closed).</summary>
        public void StopRecording()
        {
            if (!_recording) return;
            _recording = false;
            Restart();
        }

        void Update()
        {
            if (_opening != null && _opening.IsCompleted) AdoptOpened();
            if (_engine == null || status != MocapComponentStatus.Running) return;
            try
            {
                bool allEnded = true;
                for (int c = 0; c < _latest.Length; c++)
                {
                    var solver = _engine.Solver;
                    if (solver.IsEndOfStream(c)) continue;
                    allEnded = false;
                    // Drain everything solved since the last frame, keep the newest.
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
                    if (loopPlayback) Restart();
                    else SetStatus(MocapComponentStatus.Ended, "");
                }
            }
            catch (Exception e)
            {
                Fail(e.Message);
                Close();
                status = MocapComponentStatus.Failed;
                return;
            }
            if (Time.unscaledTime >= _nextStatusText)
            {
                _nextStatusText = Time.unscaledTime + 0.5f;
                try { statusText = BuildStatusText(); }
                catch (MocapException e) { statusText = e.Message; } // a status line must not stop the capture
            }
        }

        void RaisePoseSolved(int character, int count)
        {
            for (int i = 0; i < count; i++)
            {
                // A failing listener must not stop the capture (or the other listeners' frames).
                try { PoseSolved?.Invoke(character, in _drain[i]); }
                catch (Exception e) { Debug.LogException(e, this); }
            }
        }

        void AdoptOpened()
        {
            var task = _opening;
            _opening = null;
            if (task.Status != TaskStatus.RanToCompletion)
            {
                var e = task.Exception?.GetBaseException();
                Fail(e?.Message ?? "opening was cancelled");
                return;
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
            SetStatus(MocapComponentStatus.Running, "");
            try { Opened?.Invoke(this); }
            catch (Exception e) { Debug.LogException(e, this); }
        }

        /// <summary>
        /// The character's newest pose (model frame), or false before its first pose. Returns a
        /// reference into the component's buffer: valid until the next Update. Allocates nothing.
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

        /// <summary>Save a character's calibration (load it later through the settings' calibration file).</summary>
        public void SaveCalibration(int character, string path)
        {
            var session = GetSession(character) ?? throw new InvalidOperationException("the session is not running");
            session.Calibration.Save(path);
        }

        // Reused: the text is rebuilt twice a second for the inspector.
        readonly System.Text.StringBuilder _statusBuilder = new System.Text.StringBuilder(512);

        string BuildStatusText()
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
                if (_recording) text.Append(", recording ").Append(stats.CaptureBytesWritten / 1024).Append(" KiB");
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

        void SetStatus(MocapComponentStatus value, string error)
        {
            status = value;
            if (value != MocapComponentStatus.Failed) lastError = error ?? "";
        }

        void Fail(string message)
        {
            status = MocapComponentStatus.Failed;
            lastError = message;
            Debug.LogError($"[Mocap IMU] {name}: {message}", this);
        }
    }
}
