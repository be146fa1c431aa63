using System;
using UnityEngine;

namespace Mocap.Imu
{
    /// <summary>
    /// Runs the engine for the characters of a <see cref="MocapSettings"/>: the inspector-facing
    /// shell of the core's <see cref="MocapRunner"/>, which loads the model and opens the sessions
    /// and solver on a worker thread (nothing blocks the main thread) and drains every
    /// character's poses each Update into preallocated buffers (no per-frame allocation). Pose
    /// drivers, the overlay and the VMC streamer read from here.
    /// </summary>
    [DefaultExecutionOrder(-100)]
    [DisallowMultipleComponent]
    [AddComponentMenu("Mocap IMU/Mocap Session")]
    public sealed class MocapSessionComponent : MonoBehaviour
    {
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

        MocapRunner _runner;
        bool _recording;
        float _nextStatusText;

        MocapRunner Runner
        {
            get
            {
                if (_runner != null) return _runner;
                _runner = new MocapRunner { ListenerFailed = e => Debug.LogException(e, this) };
                _runner.PoseSolved += (int character, in MocapPose pose) => PoseSolved?.Invoke(character, in pose);
                _runner.Closing += () => Closing?.Invoke(this);
                _runner.ErrorReported += message => Debug.LogError($"[Mocap IMU] {name}: {message}", this);
                return _runner;
            }
        }

        /// <summary>Current status (also shown in the inspector).</summary>
        public MocapComponentStatus Status => status;

        /// <summary>The last error, "" when none.</summary>
        public string LastError => lastError;

        /// <summary>Human-readable status per character.</summary>
        public string StatusText => statusText;

        /// <summary>Characters opened (0 until <see cref="Status"/> is Running).</summary>
        public int CharacterCount => _runner?.CharacterCount ?? 0;

        /// <summary>The loaded model (null until running): skeleton, frame rate.</summary>
        public MocapModel Model => _runner?.Model;

        /// <summary>Whether raw captures are being recorded.</summary>
        public bool IsRecording => _recording && status == MocapComponentStatus.Running;

        /// <summary>The capture file each character records to while recording.</summary>
        public string GetRecordingPath(int character) => _runner?.GetRecordingPath(character) ?? string.Empty;

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
        public void Open()
        {
            if (_runner != null && (_runner.Status == MocapComponentStatus.Opening || _runner.CharacterCount > 0)) return;
            var plan = BuildPlan();
            if (plan != null) Runner.Open(plan);
            Mirror();
        }

        // Unity objects and Application.* are read here, on the main thread; null after a failure.
        MocapRunPlan BuildPlan()
        {
            try
            {
                if (settings == null || settings.characters == null || settings.characters.Count == 0)
                    throw new InvalidOperationException("no MocapSettings with at least one character assigned");
                var characters = new MocapRunCharacter[settings.characters.Count];
                for (int c = 0; c < characters.Length; c++) characters[c] = settings.characters[c].ToRunCharacter();
                return new MocapRunPlan
                {
                    ModelPath = settings.ResolveModelPath(),
                    ModelOptions = settings.ToModelOptions(),
                    SolverConfig = settings.ToSolverConfig(),
                    Characters = characters,
                    RecordingFolder = _recording ? settings.ResolveRecordingFolder() : null,
                };
            }
            catch (Exception e)
            {
                status = MocapComponentStatus.Failed;
                lastError = e.Message;
                Debug.LogError($"[Mocap IMU] {name}: {e.Message}", this);
                return null;
            }
        }

        /// <summary>Close everything (solver, sessions, model). Safe to call at any time.</summary>
        public void Close()
        {
            _runner?.Close();
            Mirror();
        }

        /// <summary>
        /// Close and open again, keeping each character's calibration (when the characters and
        /// their sensors are the same as before).
        /// </summary>
        public void Restart()
        {
            var plan = BuildPlan();
            if (plan != null) Runner.Restart(plan);
            else _runner?.Close();
            Mirror();
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
            if (_runner == null) return;
            switch (_runner.Update())
            {
                case MocapRunnerEvent.Opened:
                    Mirror();
                    try { Opened?.Invoke(this); }
                    catch (Exception e) { Debug.LogException(e, this); }
                    break;
                case MocapRunnerEvent.Ended:
                    if (loopPlayback) Restart();
                    break;
            }
            Mirror();
            if (_runner.Status == MocapComponentStatus.Running && Time.unscaledTime >= _nextStatusText)
            {
                _nextStatusText = Time.unscaledTime + 0.5f;
                try { statusText = _runner.BuildStatusText(); }
                catch (MocapException e) { statusText = e.Message; } // a status line must not stop the capture
            }
        }

        // The inspector's serialized status fields follow the runner's (a failure while building a
        // plan is the component's own and stays until the next attempt).
        void Mirror()
        {
            if (_runner == null) return;
            if (_runner.Status == MocapComponentStatus.Idle && status == MocapComponentStatus.Failed && _runner.LastError.Length == 0)
                return;
            status = _runner.Status;
            lastError = _runner.LastError;
        }

        /// <summary>
        /// The character's newest pose (model frame), or false before its first pose. Valid until
        /// the next Update. Allocates nothing.
        /// </summary>
        public bool TryGetLatestPose(int character, out MocapPose pose)
        {
            if (_runner != null) return _runner.TryGetLatestPose(character, out pose);
            pose = default;
            return false;
        }

        /// <summary>Poses received for a character since the engine opened.</summary>
        public ulong GetPoseCount(int character) => _runner?.GetPoseCount(character) ?? 0;

        /// <summary>The character's session (for stats and calibration), or null when not running.</summary>
        public MocapSession GetSession(int character) => _runner?.GetSession(character);

        /// <summary>Start a calibration step on a character (any time while running).</summary>
        public void BeginCalibration(int character, CalibrationStep step, float seconds)
        {
            if (_runner == null) throw new InvalidOperationException("the session is not running");
            _runner.BeginCalibration(character, step, seconds);
        }

        /// <summary>The latest report of a step for a character (default when not running). Allocates nothing.</summary>
        public CalibrationReport GetCalibrationReport(int character, CalibrationStep step) =>
            _runner != null ? _runner.GetCalibrationReport(character, step) : default;

        /// <summary>Clear a character's recurrent state and root motion (after a new calibration).</summary>
        public void ResetCharacter(int character) => _runner?.ResetCharacter(character);

        /// <summary>
        /// Change a running character's performer height (metres, 0: the model's training height),
        /// e.g. from an in-game menu; the settings' value applies at the next start.
        /// </summary>
        public void SetPerformerHeight(int character, float heightMeters)
        {
            if (_runner == null) throw new InvalidOperationException("the session is not running");
            _runner.SetCharacterHeight(character, heightMeters);
        }

        /// <summary>Save a character's calibration (load it later through the settings' calibration file).</summary>
        public void SaveCalibration(int character, string path)
        {
            if (_runner == null) throw new InvalidOperationException("the session is not running");
            _runner.SaveCalibration(character, path);
        }
    }
}
