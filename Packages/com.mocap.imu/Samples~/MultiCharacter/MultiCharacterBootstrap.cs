using Mocap.Imu;
using UnityEngine;

/// <summary>
/// Several characters on one solver (one batched inference per tick): each character has its
/// own sensor set (or capture), its own avatar and its own VMC port (39539, 39540, ...).
/// With no settings assigned it plays the package's test capture twice, at two speeds.
/// </summary>
public sealed class MultiCharacterBootstrap : MonoBehaviour
{
    [Tooltip("Settings asset with one entry per character; empty = the test capture played twice, at two speeds.")]
    public MocapSettings settings;
    [Tooltip("Distance between the avatars, metres.")]
    public float spacing = 1.5f;
    [Tooltip("Stream every character to its own VMC port on this machine.")]
    public bool streamVmc = true;
    [Tooltip("VMC port of the first character; the next ones count up from it.")]
    public int firstVmcPort = 39539;

    void Awake()
    {
        if (settings == null)
        {
            settings = ScriptableObject.CreateInstance<MocapSettings>();
            settings.characters.Clear();
            for (int c = 0; c < 2; c++)
            {
                settings.characters.Add(new MocapCharacterSource
                {
                    name = "Performer " + (c + 1),
                    source = MocapSourceKind.Replay,
                    playbackRealtime = true,
                    playbackSpeed = c == 0 ? 1f : 1.5f,
                });
            }
        }
        var stage = gameObject.AddComponent<MocapStage>();
        stage.Build();
        var sessionObject = new GameObject("Mocap Session");
        sessionObject.SetActive(false);
        var session = sessionObject.AddComponent<MocapSessionComponent>();
        session.settings = settings;
        session.loopPlayback = true;
        VmcStreamComponent vmc = null;
        if (streamVmc)
        {
            vmc = sessionObject.AddComponent<VmcStreamComponent>();
            vmc.session = session;
            vmc.destinations.Clear();
        }
        sessionObject.SetActive(true);

        Transform first = null;
        for (int c = 0; c < settings.characters.Count; c++)
        {
            var animator = ProceduralHumanoid.Create(settings.characters[c].name, new Vector3(c * spacing, 0f, 0f));
            var driver = animator.gameObject.AddComponent<HumanoidPoseDriver>();
            driver.session = session;
            driver.character = c;
            if (vmc != null) vmc.destinations.Add(new VmcDestination { character = c, address = "127.0.0.1:" + (firstVmcPort + c) });
            if (first == null) first = animator.transform;
        }
        stage.Frame(first);
    }
}
