using System;
using System.Collections.Generic;
using UnityEngine;

namespace Mocap.Imu
{
    /// <summary>One VMC destination: a character of the session to a receiver.</summary>
    [Serializable]
    public sealed class VmcDestination
    {
        [Tooltip("Index of the character in the session's settings.")]
        [Min(0)] public int character;
        [Tooltip("\"host:port\"; VMC receivers usually listen on 39539 (one port per avatar).")]
        public string address = VmcSender.DefaultDestination;
    }

    /// <summary>
    /// Streams the session's characters to VMC receivers (VSeeFace, Warudo, another Unity app):
    /// several characters to several ports, one core <see cref="VmcSender"/> each. Sends each
    /// character's newest pose once per new pose; nothing is allocated per frame.
    /// </summary>
    [DefaultExecutionOrder(-50)]
    [DisallowMultipleComponent]
    [AddComponentMenu("Mocap IMU/VMC Stream")]
    public sealed class VmcStreamComponent : MonoBehaviour
    {
        [Tooltip("The session whose poses are streamed.")]
        public MocapSessionComponent session;
        [Tooltip("One receiver per entry: which character goes to which host:port.")]
        public List<VmcDestination> destinations = new List<VmcDestination> { new VmcDestination() };
        [Tooltip("Bundles per second at most (0 = every pose).")]
        [Min(0f)] public float maxRateHz = 60f;
        [Tooltip("Allow receivers on other machines (off: loopback only).")]
        public bool allowRemote;

        [Header("Status (read only)")]
        [Tooltip("Per destination: bundles sent and failed sends, or why it could not be opened.")]
        [SerializeField, ReadOnlyField(6)] string statusText = "";

        VmcSender[] _senders = Array.Empty<VmcSender>();
        ulong[] _lastSequence = Array.Empty<ulong>();
        bool[] _sentAny = Array.Empty<bool>();
        // The destinations' characters as opened: the inspector list may change during Play.
        int[] _characters = Array.Empty<int>();
        float _nextStatus;

        MocapModel _openedFor;

        void OnDisable() => CloseSenders();

        void OnDestroy() => CloseSenders();

        void OpenSenders(MocapSessionComponent s)
        {
            CloseSenders();
            _openedFor = s.Model;
            var options = new VmcOptions { MaxRateHz = maxRateHz, AllowRemote = allowRemote };
            _senders = new VmcSender[destinations.Count];
            _lastSequence = new ulong[destinations.Count];
            _sentAny = new bool[destinations.Count];
            _characters = new int[destinations.Count];
            _errors = new string[destinations.Count];
            for (int i = 0; i < destinations.Count; i++) _characters[i] = destinations[i].character;
            var text = new System.Text.StringBuilder();
            for (int i = 0; i < destinations.Count; i++)
            {
                try
                {
                    _senders[i] = VmcSender.Open(s.Model, destinations[i].address, options);
                }
                catch (MocapException e)
                {
                    _errors[i] = $"{destinations[i].address}: {e.Message}";
                    text.Append(_errors[i]).Append('\n');
                    Debug.LogError($"[Mocap IMU] VMC {destinations[i].address}: {e.Message}", this);
                }
            }
            statusText = text.ToString();
        }

        // Why destination i has no sender (it failed to open or to send), else null.
        string[] _errors = Array.Empty<string>();

        void CloseSenders()
        {
            _openedFor = null;
            foreach (var sender in _senders) sender?.Dispose();
            _senders = Array.Empty<VmcSender>();
        }

        void Update()
        {
            if (session == null) return;
            // (Re)open for each engine the session opens; senders keep their own skeleton copy.
            var model = session.Status == MocapComponentStatus.Running ? session.Model : null;
            if (model != _openedFor || (model != null && destinations.Count != _senders.Length))
            {
                if (model != null) OpenSenders(session);
                else CloseSenders();
            }
            for (int i = 0; i < _senders.Length; i++)
            {
                var sender = _senders[i];
                if (sender == null) continue;
                if (!session.TryGetLatestPose(_characters[i], out var pose)) continue;
                if (_sentAny[i] && pose.Sequence == _lastSequence[i]) continue;
                _lastSequence[i] = pose.Sequence;
                _sentAny[i] = true;
                try
                {
                    sender.Send(in pose);
                }
                catch (MocapException e)
                {
                    // Reported once; the other destinations keep streaming.
                    Debug.LogError($"[Mocap IMU] VMC {sender.Destination}: {e.Message}; this destination stops", this);
                    _errors[i] = $"{sender.Destination}: {e.Message}; stopped";
                    statusText = _errors[i] + "\n";
                    sender.Dispose();
                    _senders[i] = null;
                }
            }
            if (Time.unscaledTime >= _nextStatus && _senders.Length > 0)
            {
                _nextStatus = Time.unscaledTime + 1f;
                var text = new System.Text.StringBuilder();
                for (int i = 0; i < _senders.Length; i++)
                {
                    // A destination that failed stays listed with its reason, not silently gone.
                    if (_senders[i] == null)
                    {
                        if (_errors[i] != null) text.Append(_errors[i]).Append('\n');
                        continue;
                    }
                    var st = _senders[i].GetStats();
                    text.Append(_senders[i].Destination).Append(": ").Append(st.BundlesSent).Append(" bundles, ")
                        .Append(st.SendFailures).Append(" failures\n");
                }
                statusText = text.ToString();
            }
        }
    }
}
