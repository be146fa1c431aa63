using System;
using UnityEngine;

namespace Mocap.Imu
{
    /// <summary>
    /// Run-time IMGUI overlay that walks the performer through calibration: heading step, then
    /// T-pose, each after a countdown; shows every sensor's stillness and quality from the engine's
    /// report, refuses a bad calibration with the engine's reason, and offers a heading reset.
    /// The sequence logic is the core's <see cref="CalibrationFlow"/>, the same one the editor's
    /// Calibration window uses. The panel is magnified on high-DPI screens, and with a
    /// <see cref="worldAnchor"/> (the headset camera in VR, where a screen overlay is not seen)
    /// its text is also shown on a world-space panel that follows the anchor.
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
        [Tooltip("Where the overlay is drawn on screen, in pixels at 96 dpi.")]
        public Rect area = new Rect(10, 10, 460, 330);
        [Tooltip("Magnify the overlay by the screen's density (Screen.dpi / 96) so that it stays readable on high-DPI screens.")]
        public bool scaleWithDpi = true;

        [Header("World-space panel (VR)")]
        [Tooltip("When set (the headset camera in VR), the overlay's text is also shown on a panel in front of this transform that follows it.")]
        public Transform worldAnchor;
        [Tooltip("Distance of the world-space panel in front of the anchor, metres.")]
        [Min(0.1f)] public float worldDistance = 1.2f;
        [Tooltip("Height of one line of text on the world-space panel, metres.")]
        [Min(0.001f)] public float worldLineHeight = 0.035f;

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
        // Title, session or step, instruction, progress, one line per sensor.
        readonly PanelText _worldLines = new PanelText(4 + MocapSession.MaxSensors);
        TextMesh _worldText;
        // What the TextMesh shows: its text getter makes a new string on every call.
        string _worldTextShown;
        // The built-in font of Unity 2022.2 and later (Arial.ttf before).
        const string WorldFont = "LegacyRuntime.ttf";
        const int WorldFontSize = 64;

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
            // IMGUI state is shared with every other OnGUI: leave it as it was found.
            var matrix = GUI.matrix;
            var color = GUI.color;
            bool enabledBefore = GUI.enabled;
            float scale = scaleWithDpi ? OverlayScale.For(Screen.dpi, Screen.width, Screen.height, area.xMax, area.yMax) : 1f;
            GUI.matrix = matrix * Matrix4x4.Scale(new Vector3(scale, scale, 1f));
            try
            {
                DrawPanel(enabledBefore);
            }
            finally
            {
                GUI.matrix = matrix;
                GUI.color = color;
                GUI.enabled = enabledBefore;
            }
        }

        void DrawPanel(bool enabledBefore)
        {
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
                for (int s = 0; s < report.SensorCount; s++)
                {
                    var color = GUI.color;
                    if (report.IsFinished)
                    {
                        var quality = report.GetSensor(s);
                        GUI.color = quality.IsLeftOut ? Color.yellow : quality.IsOk ? Color.green : Color.red;
                    }
                    GUILayout.Label(_sensorLines.GetLine(report, s));
                    GUI.color = color;
                }
            }

            GUILayout.BeginHorizontal();
            GUI.enabled = enabledBefore && !flow.IsBusy;
            if (GUILayout.Button("Calibrate (heading + T-pose)")) flow.StartFullCalibration(Now);
            if (GUILayout.Button("T-pose only")) flow.StartTPoseOnly(Now);
            if (GUILayout.Button("Heading reset")) flow.StartHeadingReset(Now);
            GUI.enabled = enabledBefore;
            if (flow.Phase == CalibrationFlowPhase.AwaitingTPose && GUILayout.Button("Continue")) flow.Continue(Now);
            if (flow.Phase == CalibrationFlowPhase.Refused && GUILayout.Button("Retry")) flow.Retry(Now);
            GUI.enabled = enabledBefore && flow.IsBusy;
            if (GUILayout.Button("Cancel")) flow.Cancel();
            GUI.enabled = enabledBefore;
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

        void LateUpdate()
        {
            if (worldAnchor == null || !visible)
            {
                if (_worldText != null) _worldText.gameObject.SetActive(false);
                return;
            }
            if (_worldText == null)
            {
                _worldText = CreateWorldText();
                _worldTextShown = null;
            }
            var panel = _worldText.transform;
            if (panel.parent != worldAnchor)
            {
                // A child of the anchor: it follows the head at render time, after XR tracking moves it.
                panel.SetParent(worldAnchor, false);
                panel.localRotation = Quaternion.identity;
            }
            panel.localPosition = new Vector3(0f, 0f, worldDistance);
            _worldText.characterSize = worldLineHeight * 10f / WorldFontSize;
            _worldText.gameObject.SetActive(true);

            _worldLines.Begin();
            _worldLines.Add(Title());
            if (session == null || session.Status != MocapComponentStatus.Running)
            {
                _worldLines.Add(session == null ? "Assign a MocapSessionComponent." : SessionLine(session));
            }
            else
            {
                var flow = Flow;
                _worldLines.Add(flow.Phase == CalibrationFlowPhase.Idle ? "Calibration" : CalibrationFlow.StepTitle(flow.CurrentStep));
                _worldLines.Add(flow.Instruction);
                if (flow.Phase == CalibrationFlowPhase.Collecting) _worldLines.Add(Collecting(flow.Progress));
                if (flow.TryGetReport(out var report) && report.State != CalibrationState.Idle)
                    for (int s = 0; s < report.SensorCount; s++)
                        _worldLines.Add(_sensorLines.GetLine(report, s));
            }
            var text = _worldLines.Text;
            if (!ReferenceEquals(text, _worldTextShown)) _worldText.text = _worldTextShown = text;
        }

        TextMesh CreateWorldText()
        {
            var go = new GameObject("Calibration panel");
            var mesh = go.AddComponent<TextMesh>();
            var font = Resources.GetBuiltinResource<Font>(WorldFont);
            mesh.font = font;
            mesh.fontSize = WorldFontSize;
            mesh.anchor = TextAnchor.MiddleCenter;
            mesh.alignment = TextAlignment.Left;
            mesh.color = Color.white;
            if (font != null) go.GetComponent<MeshRenderer>().sharedMaterial = font.material;
            return mesh;
        }

        void OnDisable()
        {
            if (_worldText != null) _worldText.gameObject.SetActive(false);
        }

        void OnDestroy()
        {
            if (_worldText != null) Destroy(_worldText.gameObject);
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
