using Mocap.Imu;
using UnityEngine;

/// <summary>
/// VR sample: the body comes from the sensors, the head from the XR rig where one is present
/// (an active XR device and a camera, normally the XR Origin's Main Camera). The avatar is moved
/// so its head sits under the headset and the head bone takes the headset's rotation, after the
/// pose driver has written the body. The calibration overlay's text also floats in front of the
/// headset (a screen overlay is not seen in it) and follows the head.
/// </summary>
[DefaultExecutionOrder(200)]
public sealed class VrAvatarBootstrap : MonoBehaviour
{
    [Tooltip("Settings asset to use; empty = default settings (the OS's usual serial port: COM3, /dev/ttyUSB0, /dev/cu.usbserial-0001).")]
    public MocapSettings settings;
    [Tooltip("Humanoid avatar to drive; empty = a procedural one.")]
    public Animator avatar;
    [Tooltip("The headset transform; empty = Camera.main when an XR device is active.")]
    public Transform head;
    [Tooltip("Eye position relative to the head bone, in the headset's frame: x right, y up, z forward (metres).")]
    public Vector3 eyeOffset = new Vector3(0f, 0.08f, 0.1f);

    Transform _headBone;
    CalibrationOverlay _overlay;
    Quaternion _headInFacing; // the head bone's rotation relative to the avatar's facing, at rest
    bool _xr;

    void Awake()
    {
        if (settings == null) settings = ScriptableObject.CreateInstance<MocapSettings>();
        var sessionObject = new GameObject("Mocap Session");
        sessionObject.SetActive(false);
        var session = sessionObject.AddComponent<MocapSessionComponent>();
        session.settings = settings;
        sessionObject.SetActive(true);
        _overlay = sessionObject.AddComponent<CalibrationOverlay>();
        _overlay.session = session;

        if (avatar == null) avatar = ProceduralHumanoid.Create("Avatar", Vector3.zero);
        var driver = avatar.gameObject.AddComponent<HumanoidPoseDriver>();
        driver.session = session;
        driver.rootMotion = Mocap.Imu.Retarget.RootMotionMode.InPlace; // the headset places the avatar
        _headBone = avatar.GetBoneTransform(HumanBodyBones.Head);
        // Imported rigs' head bones have their own axes: keep them relative to the headset's.
        if (_headBone != null) _headInFacing = Quaternion.Inverse(avatar.transform.rotation) * _headBone.rotation;
    }

    void LateUpdate()
    {
        _xr = UnityEngine.XR.XRSettings.isDeviceActive;
        var hmd = head != null ? head : (_xr && Camera.main != null ? Camera.main.transform : null);
        _overlay.worldAnchor = hmd;
        if (hmd == null || _headBone == null) return; // no XR rig: the sensors' head is kept
        // Head rotation from the headset; body translated so the eyes are at the headset.
        _headBone.rotation = hmd.rotation * _headInFacing;
        Vector3 eyes = _headBone.position + hmd.rotation * eyeOffset;
        Vector3 shift = hmd.position - eyes;
        shift.y = 0f; // height stays the body's: feet on the floor
        avatar.transform.position += shift;
    }
}
