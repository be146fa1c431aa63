using Mocap.Imu;
using UnityEngine;

/// <summary>
/// Live sample: builds the scene at run time. Put it on an empty GameObject in an empty scene,
/// set the serial port (or assign a MocapSettings asset), optionally assign your own Humanoid
/// avatar (in its T-pose, or set restPose to AlignToSmplTPose), and press Play.
/// </summary>
public sealed class LiveAvatarBootstrap : MonoBehaviour
{
    [Tooltip("Settings asset to use; empty = default settings with the serial port below.")]
    public MocapSettings settings;
    [Tooltip("Serial port of the HiPNUC receiver when no settings asset is assigned.")]
    public string serialPort = SerialPortDefaults.DefaultPort(PlayerPaths.CurrentOs());
    [Tooltip("Humanoid avatar to drive; empty = a procedural one.")]
    public Animator avatar;
    [Tooltip("TPose: the avatar's bind pose is a T-pose. AlignToSmplTPose: any bind pose, straightened to the model's T-pose.")]
    public Mocap.Imu.Retarget.RigRestPose restPose = Mocap.Imu.Retarget.RigRestPose.TPose;
    [Tooltip("Also add a PhysicsCharacter (ArticulationBody) to the avatar.")]
    public bool physicsCharacter;

    void Awake()
    {
        if (settings == null)
        {
            settings = ScriptableObject.CreateInstance<MocapSettings>();
            settings.characters[0].source = MocapSourceKind.Serial;
            settings.characters[0].port = serialPort;
        }
        var stage = gameObject.AddComponent<MocapStage>();
        stage.Build();
        var sessionObject = new GameObject("Mocap Session");
        sessionObject.SetActive(false);
        var session = sessionObject.AddComponent<MocapSessionComponent>();
        session.settings = settings;
        sessionObject.SetActive(true);

        if (avatar == null) avatar = ProceduralHumanoid.Create("Avatar", Vector3.zero);
        var driver = avatar.gameObject.AddComponent<HumanoidPoseDriver>();
        driver.session = session;
        driver.restPose = restPose;
        if (physicsCharacter) avatar.gameObject.AddComponent<PhysicsCharacter>();

        var overlay = sessionObject.AddComponent<CalibrationOverlay>();
        overlay.session = session;
        stage.Frame(avatar.transform);
    }
}
