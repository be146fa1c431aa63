// Window > Mocap > Calibration: walks the user through the heading step and the T-pose step with a
// countdown, shows per-sensor stillness/quality, shows a refusal with the engine's reason, and
// offers a heading reset. Every decision is the core's CalibrationFlow / CalibrationQuality; this
// window only draws them and forwards buttons. Works in Play Mode, on a running MocapSessionComponent.

using System;
using UnityEditor;
using UnityEngine;

namespace Mocap.Imu.Editor
{
    public sealed class CalibrationWindow : EditorWindow
    {
        /// <summary>Calibration steps of one character of a MocapSessionComponent.</summary>
        sealed class ComponentTarget : ICalibrationTarget
        {
            readonly MocapSessionComponent _component;
            readonly int _character;

            public ComponentTarget(MocapSessionComponent component, int character)
            {
                _component = component;
                _character = character;
            }

            public void BeginCalibration(CalibrationStep step, float durationSeconds)
            {
                if (!_component) throw new InvalidOperationException("the Mocap Session component was destroyed");
                _component.BeginCalibration(_character, step, durationSeconds);
            }

            public CalibrationReport GetCalibrationReport(CalibrationStep step)
            {
                if (!_component) throw new InvalidOperationException("the Mocap Session component was destroyed");
                return _component.GetCalibrationReport(_character, step);
            }
        }

        [SerializeField] MocapSessionComponent component;
        [SerializeField] int character;
        [SerializeField] float countdownSeconds = 3f;
        CalibrationFlow _flow;
        MocapSessionComponent _flowComponent;
        int _flowCharacter = -1;
        Vector2 _scroll;

        [MenuItem("Window/Mocap/Calibration")]
        public static void Open()
        {
            var window = GetWindow<CalibrationWindow>();
            window.titleContent = new GUIContent("Mocap Calibration");
            window.minSize = new Vector2(380, 320);
            window.Show();
        }

        void OnEnable() => EditorApplication.update += Tick;

        void OnDisable()
        {
            EditorApplication.update -= Tick;
            _flow?.Cancel();
        }

        void Tick()
        {
            if (_flow != null && _flow.Update(EditorApplication.timeSinceStartup)) Repaint();
            else if (_flow != null && _flow.IsBusy) Repaint();
        }

        CalibrationFlow Flow()
        {
            if (_flow != null && _flowComponent == component && _flowCharacter == character) return _flow;
            _flow?.Cancel();
            _flowComponent = component;
            _flowCharacter = character;
            _flow = component ? new CalibrationFlow(new ComponentTarget(component, character)) : null;
            if (_flow != null) _flow.StepFinished += OnStepFinished;
            return _flow;
        }

        void OnStepFinished(CalibrationReport report)
        {
            // New calibration: the model's recurrent state and root motion start over.
            if (report.State == CalibrationState.Accepted && _flowComponent) _flowComponent.ResetCharacter(_flowCharacter);
            Repaint();
        }

        void OnGUI()
        {
            _scroll = EditorGUILayout.BeginScrollView(_scroll);
            if (!component) component = FindAnyObjectByType<MocapSessionComponent>();
            component = (MocapSessionComponent)EditorGUILayout.ObjectField("Session", component, typeof(MocapSessionComponent), true);
            int characters = component ? Math.Max(1, component.CharacterCount) : 1;
            character = Mathf.Clamp(EditorGUILayout.IntSlider("Character", character, 0, characters - 1), 0, characters - 1);
            countdownSeconds = EditorGUILayout.Slider("Countdown (s)", countdownSeconds, 0f, 10f);

            if (!Application.isPlaying || !component || component.GetSession(character) == null)
            {
                EditorGUILayout.HelpBox("Enter Play Mode with a running Mocap Session (sensors connected or a capture playing) to calibrate.",
                                        MessageType.Info);
                EditorGUILayout.EndScrollView();
                return;
            }

            var flow = Flow();
            flow.Settings.CountdownSeconds = countdownSeconds;
            double now = EditorApplication.timeSinceStartup;

            EditorGUILayout.Space();
            var type = flow.Phase == CalibrationFlowPhase.Refused ? MessageType.Error
                : flow.Phase == CalibrationFlowPhase.Complete ? MessageType.None : MessageType.Info;
            EditorGUILayout.HelpBox(flow.Instruction, type);
            if (flow.Phase == CalibrationFlowPhase.Countdown)
                EditorGUILayout.LabelField(flow.CountdownDisplay.ToString(), new GUIStyle(EditorStyles.boldLabel) { fontSize = 32, alignment = TextAnchor.MiddleCenter }, GUILayout.Height(40));
            if (flow.Phase == CalibrationFlowPhase.Collecting)
                EditorGUI.ProgressBar(EditorGUILayout.GetControlRect(false, 18), flow.Progress, $"{CalibrationFlow.StepTitle(flow.CurrentStep)} {flow.Progress:P0}");

            // A click changes which buttons exist: leave this GUI pass at once (ExitGUI), or the
            // layout laid out for the old state no longer matches the controls of the new one.
            using (new EditorGUILayout.HorizontalScope())
            {
                using (new EditorGUI.DisabledScope(flow.IsBusy))
                {
                    if (GUILayout.Button("Calibrate (heading + T-pose)")) { flow.StartFullCalibration(now); GUIUtility.ExitGUI(); }
                    if (GUILayout.Button("T-pose only")) { flow.StartTPoseOnly(now); GUIUtility.ExitGUI(); }
                    if (GUILayout.Button("Heading reset")) { flow.StartHeadingReset(now); GUIUtility.ExitGUI(); }
                }
            }
            using (new EditorGUILayout.HorizontalScope())
            {
                if (flow.Phase == CalibrationFlowPhase.AwaitingTPose && GUILayout.Button("Continue (T-pose)")) { flow.Continue(now); GUIUtility.ExitGUI(); }
                if (flow.Phase == CalibrationFlowPhase.Refused && GUILayout.Button("Retry")) { flow.Retry(now); GUIUtility.ExitGUI(); }
                if (flow.IsBusy && GUILayout.Button("Cancel")) { flow.Cancel(); GUIUtility.ExitGUI(); }
            }

            DrawSensors(flow);
            DrawCalibrationState();
            EditorGUILayout.EndScrollView();
        }

        static void DrawSensors(CalibrationFlow flow)
        {
            if (!flow.TryGetReport(out var report) || !report.IsFinished) return;
            EditorGUILayout.Space();
            EditorGUILayout.LabelField($"{CalibrationFlow.StepTitle(report.Step)}: {report.State}", EditorStyles.boldLabel);
            foreach (var sensor in CalibrationQuality.Summarize(report))
            {
                using (new EditorGUILayout.VerticalScope(EditorStyles.helpBox))
                {
                    var label = $"{CalibrationQuality.SensorName(sensor.Segment)}: {(sensor.IsLeftOut ? "left out (optional)" : sensor.IsOk ? "OK" : "refused")}";
                    EditorGUI.ProgressBar(EditorGUILayout.GetControlRect(false, 16), sensor.Stillness, $"{label}  (stillness {sensor.Stillness:P0})");
                    EditorGUILayout.LabelField(sensor.Text, EditorStyles.miniLabel);
                    if (sensor.Problems.Count > 0)
                        EditorGUILayout.LabelField(string.Join("; ", sensor.Problems), EditorStyles.wordWrappedMiniLabel);
                }
            }
        }

        void DrawCalibrationState()
        {
            var session = component.GetSession(character);
            if (session == null) return;
            try
            {
                var calibration = session.Calibration;
                EditorGUILayout.Space();
                EditorGUILayout.LabelField("Calibration in use", calibration.IsComplete
                    ? $"complete (all {calibration.SensorCount} sensors)"
                    : $"{Calibrated(calibration)} (heading mask 0x{calibration.HeadingMask:X4})");
                // An optional sensor left out leaves the calibration incomplete but usable.
                using (new EditorGUI.DisabledScope(calibration.ValidMask == 0))
                {
                    if (GUILayout.Button("Save Calibration..."))
                    {
                        var path = EditorUtility.SaveFilePanel("Save calibration", "", "calibration.txt", "txt");
                        if (!string.IsNullOrEmpty(path)) component.SaveCalibration(character, path);
                        GUIUtility.ExitGUI(); // the modal dialog broke this pass's layout
                    }
                }
            }
            catch (Exception e) when (e is MocapException || e is InvalidOperationException || e is ObjectDisposedException)
            {
                EditorGUILayout.HelpBox(e.Message, MessageType.Warning);
            }
        }

        // "5 of 7 sensors calibrated; not: chest, head".
        static string Calibrated(in CalibrationData calibration)
        {
            int done = 0;
            var missing = new System.Text.StringBuilder();
            for (int i = 0; i < calibration.SensorCount; i++)
            {
                if ((calibration.ValidMask & (1u << i)) != 0) done++;
                else missing.Append(missing.Length == 0 ? "; not: " : ", ").Append(CalibrationQuality.SensorName(calibration.GetSegment(i)));
            }
            return $"{done} of {calibration.SensorCount} sensors calibrated{missing}";
        }
    }
}
