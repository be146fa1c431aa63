// Inspector of MocapSessionComponent: its serialized fields, then (in Play Mode) status and errors,
// one box per character (source, frames, calibration, latest pose), and the take buttons (start /
// stop an AnimationClip recording of the driven avatar, export the last take to BVH).
//
// The runtime component is read through MocapComponentBridge, which looks its members up by name,
// so this editor keeps compiling while the runtime API settles; a member it cannot find shows as
// "not reported by the component" instead of breaking the Editor assembly.

using System;
using System.Collections;
using System.IO;
using System.Reflection;
using Mocap.Imu.Recording;
using UnityEditor;
using UnityEngine;

namespace Mocap.Imu.Editor
{
    /// <summary>Reads a MocapSessionComponent by member name (see the file comment).</summary>
    public static class MocapComponentBridge
    {
        const BindingFlags Flags = BindingFlags.Instance | BindingFlags.Public | BindingFlags.NonPublic;

        /// <summary>The first readable property or field among <paramref name="names"/>, or null.</summary>
        public static object Read(object target, params string[] names)
        {
            if (target == null) return null;
            var type = target.GetType();
            foreach (var name in names)
            {
                var p = type.GetProperty(name, Flags);
                if (p != null && p.GetIndexParameters().Length == 0)
                {
                    try { return p.GetValue(target); }
                    catch (TargetInvocationException) { return null; }
                }
                var f = type.GetField(name, Flags);
                if (f != null) return f.GetValue(target);
            }
            return null;
        }

        /// <summary>Characters the component runs (count of its character list), 0 when unknown.</summary>
        public static int CharacterCount(Component component)
        {
            var n = Read(component, "CharacterCount");
            if (n is int count) return count;
            return Read(component, "Characters", "characters") is ICollection list ? list.Count : 0;
        }

        /// <summary>The session feeding character <paramref name="character"/>, or null.</summary>
        public static MocapSession Session(Component component, int character)
        {
            var m = component.GetType().GetMethod("GetSession", Flags, null, new[] { typeof(int) }, null);
            if (m != null)
            {
                try { return m.Invoke(component, new object[] { character }) as MocapSession; }
                catch (TargetInvocationException) { return null; }
            }
            return character == 0 ? Read(component, "Session") as MocapSession : null;
        }

        /// <summary>The latest solved pose of a character, when the component exposes one.</summary>
        public static bool TryGetLatestPose(Component component, int character, out MocapPose pose)
        {
            pose = default;
            var m = component.GetType().GetMethod("TryGetLatestPose", Flags, null,
                                                  new[] { typeof(int), typeof(MocapPose).MakeByRefType() }, null);
            if (m == null) return false;
            var args = new object[] { character, null };
            try
            {
                if (!(m.Invoke(component, args) is bool ok) || !ok) return false;
            }
            catch (TargetInvocationException)
            {
                return false;
            }
            pose = (MocapPose)args[1];
            return true;
        }

        /// <summary>The model's info (frame rate, skeleton), or null before the model is loaded.</summary>
        public static ModelInfo GetModelInfo(Component component) =>
            Read(component, "ModelInfo") as ModelInfo ?? (Read(component, "Model") as MocapModel)?.Info;

        /// <summary>The avatar a HumanoidPoseDriver drives from this character, else the component's own object.</summary>
        public static GameObject Avatar(Component component, int character)
        {
            foreach (var driver in UnityEngine.Object.FindObjectsByType<HumanoidPoseDriver>(FindObjectsSortMode.None))
                if (driver.session == component && driver.character == character) return driver.gameObject;
            return component.gameObject;
        }

        /// <summary>One-line status and the last error ("" when none).</summary>
        public static (string Status, string Error) StatusOf(Component component) =>
            (Read(component, "StatusText", "Status")?.ToString() ?? "not reported by the component",
             Read(component, "LastError", "Error")?.ToString() ?? string.Empty);
    }

    [CustomEditor(typeof(MocapSessionComponent), true)]
    public sealed class MocapSessionComponentEditor : UnityEditor.Editor
    {
        static string _lastPosesPath;

        public override bool RequiresConstantRepaint() => Application.isPlaying;

        public override void OnInspectorGUI()
        {
            DrawDefaultInspector();
            var component = (Component)target;
            EditorGUILayout.Space();
            EditorGUILayout.LabelField("Status", EditorStyles.boldLabel);
            if (!Application.isPlaying)
            {
                EditorGUILayout.HelpBox("Enter Play Mode to connect the sensors (or play the capture file). " +
                                        "Then calibrate with Window > Mocap > Calibration.", MessageType.Info);
                return;
            }
            var (status, error) = MocapComponentBridge.StatusOf(component);
            EditorGUILayout.LabelField("State", status);
            if (!string.IsNullOrEmpty(error)) EditorGUILayout.HelpBox(error, MessageType.Error);

            int characters = MocapComponentBridge.CharacterCount(component);
            for (int c = 0; c < characters; c++) DrawCharacter(component, c);

            EditorGUILayout.Space();
            EditorGUILayout.LabelField("Take (AnimationClip)", EditorStyles.boldLabel);
            for (int c = 0; c < Math.Max(1, characters); c++) DrawRecordButtons(component, c);
            using (new EditorGUI.DisabledScope(string.IsNullOrEmpty(_lastPosesPath)))
            {
                if (GUILayout.Button("Export Last Take to BVH..."))
                    BvhExportMenu.ExportWithDialog(_lastPosesPath);
            }
            if (GUILayout.Button("Open Calibration Window")) CalibrationWindow.Open();
        }

        static void DrawCharacter(Component component, int character)
        {
            using (new EditorGUILayout.VerticalScope(EditorStyles.helpBox))
            {
                EditorGUILayout.LabelField($"Character {character}", EditorStyles.miniBoldLabel);
                var session = MocapComponentBridge.Session(component, character);
                if (session == null)
                {
                    EditorGUILayout.LabelField("Session", "not open");
                    return;
                }
                try
                {
                    var stats = session.GetStats();
                    EditorGUILayout.LabelField("Frames", $"{stats.FramesEmitted} ({stats.FramesDropped} dropped)");
                    EditorGUILayout.LabelField("Sensors seen", SensorMask(stats.SensorsSeenMask, session.SensorCount, session.SegmentOf));
                    var lastError = stats.LastError;
                    if (!string.IsNullOrEmpty(lastError)) EditorGUILayout.HelpBox(lastError, MessageType.Warning);
                    if (stats.ReplayChunksSkipped > 0 || stats.ReplayTailDamaged)
                        EditorGUILayout.HelpBox(stats.ReplayDamage, MessageType.Warning);
                    var calibration = session.Calibration;
                    EditorGUILayout.LabelField("Calibration", calibration.IsComplete ? "complete"
                        : $"heading {SensorMask(calibration.HeadingMask, calibration.SensorCount, calibration.GetSegment)}, " +
                          $"T-pose {SensorMask(calibration.ValidMask, calibration.SensorCount, calibration.GetSegment)}");
                }
                catch (Exception e) when (e is MocapException || e is InvalidOperationException || e is ObjectDisposedException)
                {
                    EditorGUILayout.HelpBox(e.Message, MessageType.Warning);
                }
                if (MocapComponentBridge.TryGetLatestPose(component, character, out var pose))
                    EditorGUILayout.LabelField("Latest pose", $"#{pose.Sequence} at {pose.TimeSeconds:0.00} s, {pose.Flags}");
            }
        }

        // "6/7, not chest": how many of the sensors have their bit, naming the ones that do not.
        static string SensorMask(uint mask, int count, Func<int, MocapSegment> segmentOf)
        {
            int n = 0;
            var missing = new System.Text.StringBuilder();
            for (int s = 0; s < count; s++)
            {
                if ((mask & (1u << s)) != 0) n++;
                else missing.Append(missing.Length == 0 ? ", not " : " ").Append(CalibrationQuality.SensorName(segmentOf(s)));
            }
            return $"{n}/{count}{missing}";
        }

        static void DrawRecordButtons(Component component, int character)
        {
            var avatar = MocapComponentBridge.Avatar(component, character);
            var recorder = TakeRecorder.For(avatar);
            using (new EditorGUILayout.HorizontalScope())
            {
                if (recorder == null)
                {
                    if (GUILayout.Button($"Record {avatar.name}")) StartTake(component, character);
                }
                else
                {
                    var previousColor = GUI.color;
                    GUI.color = Color.red;
                    try
                    {
                        if (GUILayout.Button($"Stop ({recorder.Frames} frames, {recorder.Seconds:0.0} s)")) StopTake(recorder);
                    }
                    finally
                    {
                        GUI.color = previousColor;
                    }
                }
            }
        }

        static void StartTake(Component component, int character)
        {
            var avatar = MocapComponentBridge.Avatar(component, character);
            var info = MocapComponentBridge.GetModelInfo(component);
            PoseTake take = info != null ? new PoseTake(info) : null;
            if (take != null && component is MocapSessionComponent typed)
            {
                // Every solved pose, not the newest per rendered frame: a 30 fps editor would keep
                // half of a 60 Hz model's poses, and the take's BVH (fixed 1/rate frame time) would
                // play twice as fast as the clip.
                // The latest pose per frame names the model frame the avatar shows (the Humanoid
                // and Generic clips' key); the take's PoseTake ignores the repeat.
                TakeRecorder.PoseSource shown = (out MocapPose pose) =>
                    MocapComponentBridge.TryGetLatestPose(component, character, out pose);
                var recorder = new TakeRecorder(avatar, shown, take);
                var sessionComponent = typed;
                // Also when the take is saved on leaving Play Mode, while the session still runs.
                recorder.SavedBeside = result => KeepCaptureAndCalibration(result, sessionComponent, character);
                MocapSessionComponent.PoseHandler keep = (int c, in MocapPose pose) =>
                {
                    if (c == character && recorder.IsRecording) take.Add(pose);
                };
                typed.PoseSolved += keep;
                recorder.Ended += () => typed.PoseSolved -= keep;
                return;
            }
            TakeRecorder.PoseSource source = (out MocapPose pose) =>
                MocapComponentBridge.TryGetLatestPose(component, character, out pose);
            new TakeRecorder(avatar, source, take);
        }

        static void StopTake(TakeRecorder recorder)
        {
            var result = recorder.Stop();
            if (result.PosesPath != null) _lastPosesPath = result.PosesPath;
            if (result.MissingFrames > 0)
                Debug.LogWarning($"Mocap take: {result.MissingFrames} model frames were never shown by the editor and have no key " +
                                 "(the editor ran slower than the model); the clip interpolates across them.");
            Debug.Log($"Mocap take saved: {result.ClipPath} ({result.Frames} frames, {result.Clip.length:0.00} s)" +
                      (result.PosesPath != null ? $", poses {result.PosesPath}" : ""));
            if (result.Clip) EditorGUIUtility.PingObject(result.Clip);
        }

        static void KeepCaptureAndCalibration(TakeResult result, MocapSessionComponent component, int character)
        {
            if (result.Files == null || component == null) return;
            string project = Path.GetDirectoryName(Application.dataPath);
            try
            {
                string capture = component.GetRecordingPath(character);
                if (!string.IsNullOrEmpty(capture) && File.Exists(capture)) result.Files.KeepCapture(capture, project);
                component.SaveCalibration(character, TakeFiles.Absolute(result.Files.Calibration, project));
            }
            catch (Exception e) when (e is MocapException || e is InvalidOperationException)
            {
                Debug.LogWarning($"Mocap take: the raw capture or calibration was not kept beside {result.ClipPath}: {e.Message}");
            }
            AssetDatabase.Refresh();
        }

        /// <summary>The hotkey: stop any take, else record the selected (or first) MocapSessionComponent's character 0.</summary>
        internal static void ToggleRecordingOfActiveComponent()
        {
            if (TakeRecorder.Running.Count > 0)
            {
                foreach (var running in new System.Collections.Generic.List<TakeRecorder>(TakeRecorder.Running)) StopTake(running);
                return;
            }
            if (!Application.isPlaying)
            {
                Debug.LogWarning("Mocap: recording needs Play Mode.");
                return;
            }
            MocapSessionComponent component = null;
            if (Selection.activeGameObject) component = Selection.activeGameObject.GetComponentInParent<MocapSessionComponent>();
            if (!component) component = UnityEngine.Object.FindAnyObjectByType<MocapSessionComponent>();
            if (!component)
            {
                Debug.LogWarning("Mocap: no MocapSessionComponent in the scene to record.");
                return;
            }
            StartTake(component, 0);
        }
    }
}
