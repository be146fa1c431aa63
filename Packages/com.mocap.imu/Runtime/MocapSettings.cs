using System;
using System.Collections.Generic;
using System.IO;
using UnityEngine;

namespace Mocap.Imu
{
    /// <summary>One sensor of a character: the body segment it is strapped to and its node id.</summary>
    [Serializable]
    public sealed class MocapSensorSlot
    {
        [Tooltip("The body segment the sensor is strapped to (each segment at most once per character).")]
        public MocapSegment segment;

        [Tooltip("The sensor's HiPNUC node id, 0..255 (each node id at most once per character).")]
        public int nodeId;

        [Tooltip("The sensor may be missing: calibration leaves it out instead of refusing. Sensors the pose model marks as optional are treated so anyway.")]
        public bool optional;

        public MocapSensorSlot() { }

        public MocapSensorSlot(MocapSegment segment, int nodeId, bool optional = false)
        {
            this.segment = segment;
            this.nodeId = nodeId;
            this.optional = optional;
        }

        /// <summary>The engine's view of this slot.</summary>
        public SessionSensor ToSessionSensor() => new SessionSensor(segment, nodeId, optional);
    }

    /// <summary>Where one character's sensor data comes from.</summary>
    [Serializable]
    public sealed class MocapCharacterSource : ISerializationCallbackReceiver
    {
        [Tooltip("Shown in the inspector, the overlay and logs.")]
        public string name = "Performer";

        [Tooltip("Serial port, HID receiver, or a raw capture file played back (no sensors needed).")]
        public MocapSourceKind source = MocapSourceKind.Serial;

        [Tooltip("Serial: the port (\"COM3\", \"/dev/ttyUSB0\", \"/dev/cu.usbserial-0001\"). HID: a hidraw path, or empty to use vendor/product id.")]
        public string port = SerialPortDefaults.DefaultPort(PlayerPaths.CurrentOs());

        [Tooltip("Serial baud rate.")]
        public int baud = 460800;

        [Tooltip("HID vendor id, used when the port is empty.")]
        public int hidVendorId;

        [Tooltip("HID product id, used when the port is empty.")]
        public int hidProductId;

        [Tooltip("Playback: capture file. Relative paths resolve against the project (\"Packages/...\" works for package files).")]
        public string captureFile = "Packages/com.mocap.imu/Tests/Runtime/Fixtures/walk.cap";

        [Tooltip("Playback: at the recorded pace (off: as fast as the engine can).")]
        public bool playbackRealtime = true;

        [Tooltip("Playback: pace multiplier.")]
        [Min(0.01f)] public float playbackSpeed = 1f;

        [Tooltip("Playback: schedule the capture's own calibration windows (seconds after its first record). " +
                 "The defaults match `mocapctl synth`'s prelude: heading 0.5-2.5 s, T-pose 5.5-7.5 s.")]
        public bool playbackCalibrationWindows = true;
        [Tooltip("Playback: start of the heading window (sensors lying still), seconds after the capture's first record.")]
        public float playbackHeadingStart = 0.5f;
        [Tooltip("Playback: length of the heading window, seconds.")]
        public float playbackHeadingSeconds = 2f;
        [Tooltip("Playback: start of the T-pose window, seconds after the capture's first record.")]
        public float playbackTPoseStart = 5.5f;
        [Tooltip("Playback: length of the T-pose window, seconds.")]
        public float playbackTPoseSeconds = 2f;

        [Tooltip("The character's sensors (1 to 16): the body segment each is strapped to and its node id. " +
                 "The default is the six pelvis, wrists, shins and head on nodes 0..5; add chest for a model that uses it.")]
        public List<MocapSensorSlot> sensors = DefaultSensors();

        // Settings saved before sensor sets kept one node id per segment of the six (-1 = none);
        // read once into sensors on load, then emptied.
        [SerializeField, HideInInspector] int[] nodeIds;

        [Tooltip("Optional calibration file loaded at start (skips the calibration steps).")]
        public string calibrationFile = "";

        [Tooltip("Serial/HID: reopen the device after an unplug.")]
        public bool autoReconnect = true;

        [Tooltip("The performer's standing height in metres (1 to 2.5), or 0 for the model's training height " +
                 "(about 1.72 m). A taller or shorter performer's root then travels as far for the avatar's body " +
                 "as they did for theirs, so planted feet do not slide. Needs a model with stride scaling (the shipped ones).")]
        [Min(0f)] public float performerHeight = 0f;

        /// <summary>
        /// The engine config for this source. Main thread (paths resolve through Application);
        /// the session component sets the output rate to the model's.
        /// </summary>
        public SessionConfig ToSessionConfig(float outputRateHz, string capturePath)
        {
            SessionConfig config;
            switch (source)
            {
                case MocapSourceKind.Replay:
                    config = SessionConfig.Replay(MocapSettings.ResolvePath(captureFile), playbackRealtime, playbackSpeed);
                    break;
                case MocapSourceKind.Hid:
                    config = string.IsNullOrEmpty(port)
                        ? SessionConfig.Hid((ushort)hidVendorId, (ushort)hidProductId)
                        : SessionConfig.Hid(port);
                    break;
                default:
                    config = SessionConfig.Serial(port, baud);
                    break;
            }
            if (sensors == null || sensors.Count == 0)
                throw new ArgumentException($"character '{name}' has no sensors: add at least one to its sensor list");
            config.Sensors.Clear();
            foreach (var slot in sensors)
                if (slot != null) config.Sensors.Add(slot.ToSessionSensor());
            config.AutoReconnect = autoReconnect && source != MocapSourceKind.Replay;
            if (outputRateHz > 0f) config.OutputRateHz = outputRateHz;
            config.CapturePath = capturePath ?? string.Empty;
            return config;
        }

        /// <summary>The six pelvis, wrists, shins and head on nodes 0..5 (the engine's default set).</summary>
        public static List<MocapSensorSlot> DefaultSensors()
        {
            var list = new List<MocapSensorSlot>();
            foreach (var sensor in SensorSets.DefaultSix()) list.Add(new MocapSensorSlot(sensor.Segment, sensor.NodeId));
            return list;
        }

        void ISerializationCallbackReceiver.OnBeforeSerialize() { }

        void ISerializationCallbackReceiver.OnAfterDeserialize()
        {
            // An asset saved before sensor sets: its six node ids become the sensor list.
            if (nodeIds == null || nodeIds.Length == 0) return;
            if (nodeIds.Length == 6)
            {
                sensors = new List<MocapSensorSlot>();
                foreach (var sensor in SensorSets.FromNodeIdsOfTheSix(nodeIds))
                    sensors.Add(new MocapSensorSlot(sensor.Segment, sensor.NodeId));
            }
            nodeIds = null;
        }

        /// <summary>This source as one character of a runner's plan. Main thread (paths resolve through Application).</summary>
        public MocapRunCharacter ToRunCharacter() => new MocapRunCharacter
        {
            Name = name,
            Config = ToSessionConfig(0f, null),
            CalibrationFile = string.IsNullOrEmpty(calibrationFile) ? null : MocapSettings.ResolvePath(calibrationFile),
            HeightMeters = performerHeight,
            PlaybackWindows = source == MocapSourceKind.Replay && playbackCalibrationWindows
                ? new PlaybackCalibrationWindows(playbackHeadingStart, playbackHeadingSeconds, playbackTPoseStart, playbackTPoseSeconds)
                : (PlaybackCalibrationWindows?)null,
        };
    }

    /// <summary>
    /// Everything a <see cref="MocapSessionComponent"/> needs: the pose model and where it runs,
    /// the solver options, and one source per character. Create with Assets > Create > Mocap IMU >
    /// Settings, or ScriptableObject.CreateInstance at run time.
    /// </summary>
    [CreateAssetMenu(menuName = "Mocap IMU/Settings", fileName = "MocapSettings")]
    public sealed class MocapSettings : ScriptableObject
    {
        [Header("Pose model")]
        [Tooltip("The .onnx pose model. Relative paths resolve against the project; a player build ships it as StreamingAssets/com.mocap.imu/<file name>.")]
        public string modelPath = PlayerPaths.DefaultModelPath;

        [Tooltip("Where the model runs: CPU (always available) or CUDA (needs a CUDA build of ONNX Runtime and a GPU; refused with a clear error otherwise).")]
        public ExecutionProvider executionProvider = ExecutionProvider.Cpu;

        [Tooltip("Threads ONNX Runtime uses inside one operator. 1 runs the model on the solver's thread; more rarely help (a frame is ~0.1 ms of small operators); 0 = ONNX Runtime's own default, a thread per core whose idle threads spin and keep a core busy.")]
        [Min(0)] public int intraOpThreads = 1;

        [Tooltip("CUDA device index.")]
        [Min(0)] public int cudaDevice;

        [Tooltip("Explicit ONNX Runtime library; empty = the com.github.asus4.onnxruntime plugin for this platform.")]
        public string onnxRuntimePath = "";

        [Header("Solver")]
        [Tooltip("Planted feet hold the root back from sliding and stand on the floor.")]
        public bool driftCorrection = true;
        [Tooltip("Foot-contact probability from which a foot counts as planted.")]
        [Range(0f, 1f)] public float contactThreshold = 0.5f;
        [Tooltip("Height of the floor the planted feet stand on, metres.")]
        public float floorHeight;
        [Tooltip("Only calibrated frames are solved.")]
        public bool requireCalibration = true;
        [Tooltip("Output smoothing: cut-off frequency (Hz) for a joint at rest. Lower is smoother; 0 = off (the model's raw output).")]
        [Min(0f)] public float smoothingMinCutoffHz = 2f;
        [Tooltip("How much fast motion bypasses the smoothing (Hz per rad/s of joint speed): higher = less lag on fast moves.")]
        [Min(0f)] public float smoothingBeta = 12f;
        [Tooltip("Smoothing that waits: each pose averages the frames either side of it and comes this many frames (16.7 ms each) later, in place of the filter above. Less jitter at no accuracy cost, for recording and streaming; 0 for VR (no added latency).")]
        [Range(0, SolverConfig.MaxSmoothingDelayFrames)] public int smoothingDelayFrames;
        [Tooltip("Foot pinning: a planted foot stays where it touched down (the leg bends to reach it), sliding at most this fast (m/s). 0.06 leaves about the slide of real feet rolling heel to toe; 0 = off (the predicted legs as they are).")]
        [Range(0f, SolverConfig.MaxFootPinSlideSpeed)] public float footPinSlideSpeed = 0.06f;
        [Tooltip("Pose limits: a joint the model bends where no person's joint goes is turned back to within this many degrees of the range people's joints take. 25 keeps out poses nobody takes and leaves every other pose as it is; 0 = off.")]
        [Range(0f, SolverConfig.MaxPoseLimitDegrees)] public float poseLimitDegrees = 25f;
        [Tooltip("Chest following (a model with a chest sensor): the spine turns this share of the way from the model's chest to what the chest sensor reports. 0.5 suits the seven-sensor model; 0 = off. No effect without a chest sensor.")]
        [Range(0f, 1f)] public float chestFollowShare = 0.5f;

        [Header("Characters (one sensor set each)")]
        [Tooltip("One entry per performer: each has its own sensor set and drives its own avatar.")]
        public List<MocapCharacterSource> characters = new List<MocapCharacterSource> { new MocapCharacterSource() };

        [Header("Raw capture recording")]
        [Tooltip("Folder for recorded captures; relative to the project folder (editor) or persistentDataPath (player).")]
        public string recordingFolder = "Captures";

        /// <summary>Where this editor or player runs, for the core's path rules (main thread: reads Application).</summary>
        public static RunningContext CurrentContext()
        {
            var os = PlayerPaths.CurrentOs();
            var cpu = PlayerPaths.CurrentArchitecture();
            var context = Application.isEditor
                ? RunningContext.Editor(os, Path.GetDirectoryName(Application.dataPath), cpu)
                : RunningContext.Player(os, Application.dataPath, cpu);
            context.StreamingAssetsPath = Application.streamingAssetsPath;
            context.PersistentDataPath = Application.persistentDataPath;
            context.OnnxRuntimeOverride = Environment.GetEnvironmentVariable("MOCAP_ONNXRUNTIME_PATH");
            if (Application.isEditor)
            {
                // Unity resolves "Packages/<name>" to the package's real folder (embedded, local or PackageCache).
                context.PackageFolders["com.mocap.imu"] = Path.GetFullPath("Packages/com.mocap.imu");
                context.PackageFolders[PlayerPaths.OnnxRuntimePackage] = Path.GetFullPath("Packages/" + PlayerPaths.OnnxRuntimePackage);
            }
            return context;
        }

        /// <summary>
        /// A data file the settings name (capture, calibration): the file found, else the first
        /// place looked (the engine's error then names it). Empty stays empty.
        /// </summary>
        public static string ResolvePath(string path)
        {
            if (string.IsNullOrWhiteSpace(path)) return string.Empty;
            var lookup = PlayerPaths.FindFile(CurrentContext(), path, "file");
            return lookup.Found ? lookup.Path : lookup.Tried[0];
        }

        /// <summary>The pose model to open.</summary>
        /// <exception cref="MocapException">NotFound, naming every path tried.</exception>
        public string ResolveModelPath() => PlayerPaths.FindModel(CurrentContext(), modelPath).Require();

        /// <summary>Model options with the ONNX Runtime library of this platform (docs: "How the engine finds ONNX Runtime").</summary>
        /// <exception cref="MocapException">NotFound: the ONNX Runtime path set here does not exist.</exception>
        public ModelOptions ToModelOptions()
        {
            var lookup = PlayerPaths.FindOnnxRuntime(CurrentContext(), onnxRuntimePath);
            if (!lookup.Found && !string.IsNullOrWhiteSpace(onnxRuntimePath)) lookup.Require();
            if (!lookup.Found) Debug.LogWarning("Mocap: " + lookup.Error + "; the engine searches its own default places next.");
            return new ModelOptions
            {
                ExecutionProvider = executionProvider,
                IntraOpThreads = intraOpThreads,
                CudaDevice = cudaDevice,
                OnnxRuntimePath = lookup.Found ? lookup.Path : string.Empty,
            };
        }

        /// <summary>Solver options.</summary>
        public SolverConfig ToSolverConfig()
        {
            return new SolverConfig
            {
                DriftCorrection = driftCorrection,
                ContactThreshold = contactThreshold,
                FloorHeight = floorHeight,
                RequireCalibration = requireCalibration,
                SmoothingMinCutoffHz = smoothingMinCutoffHz,
                SmoothingBeta = smoothingBeta,
                SmoothingDelayFrames = smoothingDelayFrames,
                FootPinSlideSpeed = footPinSlideSpeed,
                PoseLimitDegrees = SolverConfig.PoseLimitFrom(poseLimitDegrees),
                ChestFollowShare = SolverConfig.ChestFollowFrom(chestFollowShare),
            };
        }

        /// <summary>Where recordings go.</summary>
        public string ResolveRecordingFolder() => PlayerPaths.RecordingFolder(CurrentContext(), recordingFolder);
    }

    /// <summary>
    /// The ONNX Runtime library shipped by com.github.asus4.onnxruntime, for the engine's
    /// explicit path (the engine's own search does not look inside Unity packages or players).
    /// The places per editor and player are the core's (PlayerPaths.FindOnnxRuntime).
    /// </summary>
    public static class OnnxRuntimeLocator
    {
        /// <summary>The first candidate that exists, else "" (let the engine search).</summary>
        public static string Find()
        {
            var lookup = PlayerPaths.FindOnnxRuntime(MocapSettings.CurrentContext());
            return lookup.Found ? lookup.Path : string.Empty;
        }
    }
}
