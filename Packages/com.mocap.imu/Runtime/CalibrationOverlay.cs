using System;
using UnityEngine;

namespace Mocap.Imu
{
    /// <summary>
    /// Run-time IMGUI overlay that walks the performer through calibration: heading step, then
    /// T-pose, each after a countdown; shows every sensor's stillness and quality from the engine's
    /// report, refuses a bad calibration with the engine's reason, and offers a heading reset.
    /// The sequence logic is the core's <see cref="CalibrationFlow"/>, the same one the editor's
    /// Calibration window uses.
    /// </summary>
    [AddComponentMenu("Mocap IMU/Calibration Overlay")]
    public sealed class CalibrationOverlay : MonoBehaviour
    {
        [Tooltip("The session whose sensors are calibrated.")]
        public MocapSessionComponent session;
        [Tooltip("Index of the character in the session's settings.")]
        [Min(0)] public int character;
        [Tooltip("Seconds to get into position before each step's window starts.")]
        [Min(0f)] public float countdownSeconds = 3f;
        [Tooltip("Seconds the heading step collects, the sensors lying still on a table.")]
        [Range(0.2f, 15f)] public float headingSeconds = 2f;
        [Tooltip("Seconds the T-pose step collects, the performer standing still in the T-pose.")]
        [Range(0.2f, 15f)] public float tPoseSeconds = 2f;
        [Tooltip("Show the overlay (the toggle key switches it at run time).")]
        public bool visible = true;
        [Tooltip("Key that shows or hides the overlay (None: no key).")]
        public KeyCode toggleKey = KeyCode.F1;
        [Tooltip("Where the overlay is drawn on screen, in pixels.")]
        public Rect area = new Rect(10, 10, 460, 330);

        /// <summary>One character of a <see cref="MocapSessionComponent"/> as a calibration target.</summary>
        sealed class CharacterTarget : ICalibrationTarget
        {
            public MocapSessionComponent Session;
            public int Character;

            public void BeginCalibration(CalibrationStep step, float durationSeconds) =>
                Session.BeginCalibration(Character, step, durationSeconds);

            public CalibrationReport GetCalibrationReport(CalibrationStep step) =>
                Session.GetCalibrationReport(Character, step);
        }

        readonly CharacterTarget _target = new CharacterTarget();
        readonly CalibrationFlowSettings _settings = new CalibrationFlowSettings();
        CalibrationFlow _flow;
        // OnGUI runs every frame: strings are rebuilt only when what they show changes.
        readonly CalibrationReportLines _sensorLines = new CalibrationReportLines();
        string _title, _titleName, _collecting, _recording, _recordingPath;
        int _collectingPercent = -1;

        /// <summary>The guided flow (phase, step, countdown, refusal reason).</summary>
        public CalibrationFlow Flow => _flow ??= new CalibrationFlow(_target, _settings);

        static double Now => Time.realtimeSinceStartupAsDouble;

        void Update()
        {
#if ENABLE_LEGACY_INPUT_MANAGER
            // Projects on the Input System package only: toggle `visible` from your own input code.
            if (toggleKey != KeyCode.None && Input.GetKeyDown(toggleKey)) visible = !visible;
#endif
            _target.Session = session;
            _target.Character = character;
            _settings.CountdownSeconds = countdownSeconds;
            _settings.HeadingSeconds = headingSeconds;
            _settings.TPoseSeconds = tPoseSeconds;
            if (session == null || session.Status != MocapComponentStatus.Running)
            {
                if (_flow != null && _flow.IsBusy) _flow.Cancel();
                return;
            }
            var before = Flow.Phase;
            if (Flow.Update(Now) && before != Flow.Phase)
            {
                // A new calibration changes every input the network sees: start its memory afresh.
                if (Flow.Phase == CalibrationFlowPhase.Complete) session.ResetCharacter(character);
                else if (Flow.Phase == CalibrationFlowPhase.Refused)
                    Debug.LogWarning($"[Mocap IMU] calibration refused: {Flow.Reason}", this);
            }
        }

        // The "Session: ..." line while not running, rebuilt only when what it shows changes.
        string _sessionLine;
        MocapComponentStatus _sessionLineStatus;
        string _sessionLineError;

        string SessionLine(MocapSessionComponent component)
        {
            var status = component.Status;
            var error = component.LastError;
            if (_sessionLine == null || status != _sessionLineStatus || !ReferenceEquals(error, _sessionLineError))
            {
                _sessionLine = $"Session: {status} {error}";
                _sessionLineStatus = status;
                _sessionLineError = error;
            }
            return _sessionLine;
        }

        void OnGUI()
        {
            if (!visible) return;
            GUILayout.BeginArea(area, GUI.skin.box);
            GUILayout.Label(Title());
            if (session == null || session.Status != MocapComponentStatus.Running)
            {
                GUILayout.Label(session == null ? "Assign a MocapSessionComponent." : SessionLine(session));
                GUILayout.EndArea();
                return;
            }

            var flow = Flow;
            GUILayout.Label(flow.Phase == CalibrationFlowPhase.Idle ? "Calibration" : CalibrationFlow.StepTitle(flow.CurrentStep));
            GUILayout.Label(flow.Instruction);
            CalibrationReport report = default;
            bool hasReport = flow.TryGetReport(out report);
            if (flow.Phase == CalibrationFlowPhase.Collecting)
                GUILayout.Label(Collecting(flow.Progress));

            // Per sensor: stillness (gyro RMS) and orientation spread over the window.
            if (hasReport && report.State != CalibrationState.Idle)
            {
                for (int s = 0; s < MocapSession.SensorCount; s++)
                {
                    var color = GUI.color;
                    if (report.IsFinished) GUI.color = report.GetSensor((MocapSegment)s).IsOk ? Color.green : Color.red;
                    GUILayout.Label(_sensorLines.GetLine(report, (MocapSegment)s));
                    GUI.color = color;
                }
            }

            GUILayout.BeginHorizontal();
            GUI.enabled = !flow.IsBusy;
            if (GUILayout.Button("Calibrate (heading + T-pose)")) flow.StartFullCalibration(Now);
            if (GUILayout.Button("T-pose only")) flow.StartTPoseOnly(Now);
            if (GUILayout.Button("Heading reset")) flow.StartHeadingReset(Now);
            GUI.enabled = true;
            if (flow.Phase == CalibrationFlowPhase.AwaitingTPose && GUILayout.Button("Continue")) flow.Continue(Now);
            if (flow.Phase == CalibrationFlowPhase.Refused && GUILayout.Button("Retry")) flow.Retry(Now);
            GUI.enabled = flow.IsBusy;
            if (GUILayout.Button("Cancel")) flow.Cancel();
            GUI.enabled = true;
            GUILayout.EndHorizontal();

            GUILayout.BeginHorizontal();
            if (GUILayout.Button(session.IsRecording ? "Stop recording" : "Record raw capture"))
            {
                if (session.IsRecording) session.StopRecording();
                else session.StartRecording();
            }
            GUILayout.EndHorizontal();
            if (session.IsRecording) GUILayout.Label(Recording(session.GetRecordingPath(character)));
            GUILayout.EndArea();
        }

        string Title()
        {
            string name = session != null ? session.GetCharacterName(character) : "no session";
            if (_title == null || name != _titleName)
            {
                _titleName = name;
                _title = "Mocap IMU - " + name;
            }
            return _title;
        }

        string Collecting(float progress)
        {
            int percent = (int)Math.Round(progress * 100f);
            if (percent != _collectingPercent)
            {
                _collectingPercent = percent;
                _collecting = $"Collecting: {percent}%";
            }
            return _collecting;
        }

        string Recording(string path)
        {
            if (_recording == null || path != _recordingPath)
            {
                _recordingPath = path;
                _recording = "Recording to " + path;
            }
            return _recording;
        }
    }
}
