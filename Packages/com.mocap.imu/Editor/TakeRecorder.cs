// Records a driven avatar in the editor. With a pose source and a model rate (a PoseTake), each new
// solved pose the avatar shows is sampled into the core's HumanoidTake (HumanoidTakeSampler): a
// Humanoid clip (RootT/RootQ and muscles through HumanPoseHandler, plays on any Humanoid avatar)
// and a Generic clip (every bone), both keyed exactly at the model's frame clock with no key
// reduction unless one is asked for. Without them, UnityEditor.Animations.GameObjectRecorder takes
// one snapshot per rendered frame as before. The solved poses go to a core PoseTake for BVH export.
// Thin: naming, timing, curves and pose bookkeeping live in the engine-free core
// (Recording/HumanoidTake.cs, TakeFiles.cs, PoseTake.cs, BvhExporter.cs).
//
// In Play Mode a snapshot is taken once per player frame after LateUpdate (a PlayerLoop system
// appended to PostLateUpdate), so the clip sees exactly the pose the driver applied that frame.
// Tests and tools call Capture(deltaTime) themselves (ManualCapture).

using System;
using System.Collections.Generic;
using System.IO;
using Mocap.Imu.Recording;
using UnityEditor;
using UnityEditor.Animations;
using UnityEditor.ShortcutManagement;
using UnityEngine;
using UnityEngine.LowLevel;

namespace Mocap.Imu.Editor
{
    /// <summary>What a finished take produced.</summary>
    public sealed class TakeResult
    {
        /// <summary>The main clip: the Humanoid one when the avatar is Humanoid, else the Generic one.</summary>
        public AnimationClip Clip;
        /// <summary>"Assets/Mocap Takes/Take ... .anim", or null when not saved.</summary>
        public string ClipPath;
        /// <summary>The Generic clip beside a Humanoid one (null when <see cref="Clip"/> is the Generic clip).</summary>
        public AnimationClip GenericClip;
        /// <summary>Its path, or null.</summary>
        public string GenericClipPath;
        /// <summary>Every file name of the take (capture and calibration go beside the clips), or null when not saved.</summary>
        public TakeFiles Files;
        /// <summary>Model frames between the first and last key that the editor never showed (0: every pose is a key).</summary>
        public long MissingFrames;
        /// <summary>The take's solved poses (null when no pose source was given).</summary>
        public PoseRecording Poses;
        /// <summary>The ".mcpose" next to the clip, or null.</summary>
        public string PosesPath;
        /// <summary>Snapshots taken.</summary>
        public int Frames;
    }

    /// <summary>Records one avatar. Start, Capture (or the player loop), Stop.</summary>
    public sealed class TakeRecorder : IDisposable
    {
        /// <summary>The source of the pose applied this frame; false when there is none.</summary>
        public delegate bool PoseSource(out MocapPose pose);

        static readonly List<TakeRecorder> Active = new List<TakeRecorder>();

        GameObjectRecorder _recorder;
        HumanoidTakeSampler _sampler;
        readonly PoseSource _poses;
        readonly PoseTake _take;
        bool _first = true;
        bool _hooked;

        /// <summary>
        /// Start recording every Transform under <paramref name="root"/> (position, rotation and
        /// scale curves). <paramref name="poses"/> and <paramref name="take"/> are optional: with
        /// them each snapshot also keeps the pose that drove it.
        /// </summary>
        public TakeRecorder(GameObject root, PoseSource poses = null, PoseTake take = null, bool manualCapture = false)
        {
            Root = root ? root : throw new ArgumentNullException(nameof(root));
            _poses = poses;
            _take = take;
            _recorder = new GameObjectRecorder(root);
            _recorder.BindComponentsOfType<Transform>(root, true);
            if (poses != null && take != null) _sampler = new HumanoidTakeSampler(root, take.FrameRate);
            ManualCapture = manualCapture;
            StartedAt = DateTime.Now;
            Active.Add(this);
            if (!manualCapture) Hook();
        }

        /// <summary>The recorded hierarchy's root.</summary>
        public GameObject Root { get; }
        /// <summary>The caller takes the snapshots (no player loop hook).</summary>
        public bool ManualCapture { get; }
        /// <summary>Local time the take began (names the clip).</summary>
        public DateTime StartedAt { get; }
        /// <summary>Snapshots so far.</summary>
        public int Frames { get; private set; }
        /// <summary>Recorded seconds (the recorder's clock).</summary>
        public float Seconds => _recorder != null ? _recorder.currentTime : 0f;
        /// <summary>Still recording.</summary>
        public bool IsRecording => _recorder != null;
        /// <summary>Poses kept so far.</summary>
        public int PoseCount => _take?.Count ?? 0;
        /// <summary>Key reduction of the saved clips: none by default (every model frame a key).</summary>
        public KeyReduction Reduction { get; set; } = KeyReduction.None;

        /// <summary>
        /// Called after a take is saved (by <see cref="Stop"/> with a folder, or on leaving Play
        /// Mode) to put more files beside its clips, e.g. the raw capture and the calibration.
        /// </summary>
        public Action<TakeResult> SavedBeside;

        /// <summary>Raised once when the take stops, saved or not (listeners unsubscribe here).</summary>
        public event Action Ended;

        /// <summary>Any recorder running for this root.</summary>
        public static TakeRecorder For(GameObject root) => Active.Find(r => r.Root == root);

        /// <summary>Recorders running now.</summary>
        public static IReadOnlyList<TakeRecorder> Running => Active;

        /// <summary>
        /// Take one snapshot; <paramref name="deltaTime"/> is the time since the previous one (the
        /// first snapshot is at time 0 whatever is passed, so N snapshots make a clip of N-1 steps).
        /// </summary>
        public void Capture(float deltaTime)
        {
            if (_recorder == null) throw new InvalidOperationException("the take is stopped");
            if (!Root) throw new InvalidOperationException("the recorded object was destroyed");
            _recorder.TakeSnapshot(_first ? 0f : Mathf.Max(0f, deltaTime));
            _first = false;
            Frames++;
            if (_poses != null && _poses(out var pose))
            {
                // The avatar shows this pose now: one sample per new model frame (repeats are ignored).
                _sampler?.Sample(pose.Sequence);
                _take?.Add(pose);
            }
        }

        /// <summary>
        /// Stop and save: the clip as "&lt;folder&gt;/&lt;prefix&gt; Take yyyy-MM-dd HH-mm-ss.anim" (numbered when
        /// taken) and the poses as a ".mcpose" beside it. <paramref name="folder"/> null = don't
        /// save an asset (the clip is returned only).
        /// </summary>
        public TakeResult Stop(string folder = TakeNaming.DefaultFolder, string prefix = null)
        {
            if (_recorder == null) throw new InvalidOperationException("the take is already stopped");
            Unhook();
            Active.Remove(this);
            RaiseEnded();
            var result = new TakeResult { Frames = Frames };
            var name = TakeNaming.TakeName(StartedAt, prefix ?? (Root ? Root.name : null));
            AnimationClip humanoid = null, generic;
            if (_sampler != null && _sampler.Take.Count > 0)
            {
                humanoid = _sampler.HumanoidClip(name, Reduction);
                generic = _sampler.GenericClip(name + TakeFiles.GenericSuffix, Reduction);
                result.MissingFrames = _sampler.Take.MissingFrames;
            }
            else
            {
                generic = new AnimationClip { name = name };
                if (Frames > 0) _recorder.SaveToClip(generic);
            }
            ReleaseRecorder();
            result.Clip = humanoid ? humanoid : generic;
            result.GenericClip = humanoid ? generic : null;
            if (_take != null && _take.Count > 0) result.Poses = _take.ToRecording();
            if (folder == null) return result;

            EnsureFolder(folder);
            result.Files = TakeFiles.Reserve(folder, name, p => AssetDatabase.LoadMainAssetAtPath(p) != null || File.Exists(p));
            if (humanoid)
            {
                result.ClipPath = result.Files.HumanoidClip;
                result.GenericClipPath = result.Files.GenericClip;
                humanoid.name = Path.GetFileNameWithoutExtension(result.ClipPath);
                generic.name = Path.GetFileNameWithoutExtension(result.GenericClipPath);
                AssetDatabase.CreateAsset(humanoid, result.ClipPath);
                AssetDatabase.CreateAsset(generic, result.GenericClipPath);
            }
            else
            {
                result.ClipPath = result.Files.GenericClip;
                generic.name = Path.GetFileNameWithoutExtension(result.ClipPath);
                AssetDatabase.CreateAsset(generic, result.ClipPath);
            }
            if (result.Poses != null)
            {
                result.PosesPath = result.Files.Poses;
                result.Poses.Save(Path.GetFullPath(result.PosesPath));
                AssetDatabase.ImportAsset(result.PosesPath);
            }
            AssetDatabase.SaveAssets();
            // The clips are saved: files beside them are extras that must not lose the take.
            try { SavedBeside?.Invoke(result); }
            catch (Exception e) { Debug.LogException(e); }
            return result;
        }

        /// <summary>Stop without saving.</summary>
        public void Dispose()
        {
            if (_recorder == null) return;
            Unhook();
            Active.Remove(this);
            RaiseEnded();
            ReleaseRecorder();
        }

        // GameObjectRecorder is a native Unity object: dropping the reference would leak it.
        void ReleaseRecorder()
        {
            _recorder.ResetRecording();
            UnityEngine.Object.DestroyImmediate(_recorder);
            _recorder = null;
            _sampler?.Dispose();
            _sampler = null;
        }

        void RaiseEnded()
        {
            var ended = Ended;
            Ended = null;
            try { ended?.Invoke(); }
            catch (Exception e) { Debug.LogException(e); }
        }

        /// <summary>Create an "Assets/..." folder chain if missing.</summary>
        public static void EnsureFolder(string folder)
        {
            folder = folder.Replace('\\', '/').TrimEnd('/');
            if (AssetDatabase.IsValidFolder(folder)) return;
            int slash = folder.LastIndexOf('/');
            if (slash <= 0) throw new ArgumentException($"'{folder}' is not under Assets/", nameof(folder));
            var parent = folder.Substring(0, slash);
            EnsureFolder(parent);
            AssetDatabase.CreateFolder(parent, folder.Substring(slash + 1));
        }

        // ---- player loop hook: one snapshot per frame, after LateUpdate ----------------------

        /// <summary>Marks our system in the player loop.</summary>
        struct MocapTakeSnapshot
        {
        }

        static bool _loopInstalled;

        void Hook()
        {
            _hooked = true;
            if (_loopInstalled) return;
            var loop = PlayerLoop.GetCurrentPlayerLoop();
            if (InsertInto(ref loop, typeof(UnityEngine.PlayerLoop.PostLateUpdate)))
            {
                PlayerLoop.SetPlayerLoop(loop);
                _loopInstalled = true;
            }
            else Debug.LogWarning("Mocap take: PostLateUpdate not found in the player loop; call Capture() yourself.");
        }

        void Unhook()
        {
            if (!_hooked) return;
            _hooked = false;
            if (!_loopInstalled || Active.Exists(r => r != this && r._hooked)) return;
            var loop = PlayerLoop.GetCurrentPlayerLoop();
            RemoveFrom(ref loop);
            PlayerLoop.SetPlayerLoop(loop);
            _loopInstalled = false;
        }

        static void TickAll()
        {
            if (!EditorApplication.isPlaying || EditorApplication.isPaused) return;
            // Copy: a failing recorder removes itself.
            foreach (var recorder in Active.ToArray())
            {
                if (!recorder._hooked) continue;
                try
                {
                    recorder.Capture(Time.deltaTime);
                }
                catch (Exception e)
                {
                    Debug.LogError($"Mocap take of '{(recorder.Root ? recorder.Root.name : "?")}' stopped: {e.Message}");
                    recorder.Dispose();
                }
            }
        }

        static bool InsertInto(ref PlayerLoopSystem system, Type phase)
        {
            if (system.subSystemList == null) return false;
            for (int i = 0; i < system.subSystemList.Length; i++)
            {
                ref var sub = ref system.subSystemList[i];
                if (sub.type == phase)
                {
                    var list = new List<PlayerLoopSystem>(sub.subSystemList ?? Array.Empty<PlayerLoopSystem>());
                    list.RemoveAll(s => s.type == typeof(MocapTakeSnapshot));
                    list.Add(new PlayerLoopSystem { type = typeof(MocapTakeSnapshot), updateDelegate = TickAll });
                    sub.subSystemList = list.ToArray();
                    return true;
                }
                if (InsertInto(ref sub, phase)) return true;
            }
            return false;
        }

        static void RemoveFrom(ref PlayerLoopSystem system)
        {
            if (system.subSystemList == null) return;
            var list = new List<PlayerLoopSystem>(system.subSystemList);
            list.RemoveAll(s => s.type == typeof(MocapTakeSnapshot));
            for (int i = 0; i < list.Count; i++)
            {
                var sub = list[i];
                RemoveFrom(ref sub);
                list[i] = sub;
            }
            system.subSystemList = list.ToArray();
        }

        // Leaving Play Mode ends the frames: save what was recorded rather than lose it.
        [InitializeOnLoadMethod]
        static void SaveOnExitPlayMode()
        {
            EditorApplication.playModeStateChanged += state =>
            {
                if (state != PlayModeStateChange.ExitingPlayMode) return;
                foreach (var recorder in Active.ToArray())
                {
                    if (!recorder._hooked) continue;
                    // One take failing to save (a full disk) must not lose the others.
                    try
                    {
                        var result = recorder.Stop();
                        Debug.Log($"Mocap take saved on leaving Play Mode: {result.ClipPath} ({result.Frames} frames)");
                    }
                    catch (Exception e)
                    {
                        Debug.LogException(e);
                    }
                }
            };
        }

        // ---- hotkey --------------------------------------------------------------------------

        /// <summary>Start/stop recording (default F10; Edit > Shortcuts > Mocap to change it).</summary>
        [Shortcut("Mocap/Start or Stop Recording", KeyCode.F10)]
        static void ToggleShortcut() => MocapSessionComponentEditor.ToggleRecordingOfActiveComponent();
    }
}
