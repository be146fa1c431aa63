using Mocap.Imu;
using UnityEngine;

/// <summary>
/// Playback sample, no sensors needed: plays a raw capture (by default the walk capture shipped
/// with the package's tests) through the engine and the model in a loop, with the calibration
/// windows recorded in the capture, onto a Humanoid avatar.
/// </summary>
public sealed class CapturePlaybackBootstrap : MonoBehaviour
{
    [Tooltip("Raw capture to play in a loop; relative paths resolve against the project.")]
    public string captureFile = "Packages/com.mocap.imu/Tests/Runtime/Fixtures/walk.cap";
    [Tooltip("Optional calibration of this capture's sensors (the Calibration window's Save, or " +
             "`mocapctl replay --save-calibration`); empty = the capture's own calibration windows.")]
    public string calibrationFile = "";
    [Tooltip("Humanoid avatar to drive; empty = a procedural one.")]
    public Animator avatar;
    [Tooltip("Playback pace multiplier.")]
    [Min(0.01f)] public float speed = 1f;
    [Tooltip("Also add a PhysicsCharacter (ArticulationBody) to the avatar.")]
    public bool physicsCharacter;

    void Awake()
    {
        var settings = ScriptableObject.CreateInstance<MocapSettings>();
        var source = settings.characters[0];
        source.name = "Playback";
        source.source = MocapSourceKind.Replay;
        source.captureFile = captureFile;
        source.playbackRealtime = true;
        source.playbackSpeed = speed;
        source.calibrationFile = calibrationFile;
        // Without a calibration file, the capture's own heading and T-pose windows calibrate it.
        source.playbackCalibrationWindows = string.IsNullOrEmpty(calibrationFile);

        var stage = gameObject.AddComponent<MocapStage>();
        stage.Build();
        var sessionObject = new GameObject("Mocap Session");
        sessionObject.SetActive(false);
        var session = sessionObject.AddComponent<MocapSessionComponent>();
        session.settings = settings;
        session.loopPlayback = true;
        sessionObject.SetActive(true);

        if (avatar == null) avatar = ProceduralHumanoid.Create("Avatar", Vector3.zero);
        var driver = avatar.gameObject.AddComponent<HumanoidPoseDriver>();
        driver.session = session;
        if (physicsCharacter) avatar.gameObject.AddComponent<PhysicsCharacter>();
        stage.Frame(avatar.transform);
    }
}
