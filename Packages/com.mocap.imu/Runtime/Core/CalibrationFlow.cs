// The guided calibration of the editor's Calibration window as a plain state machine (no Unity):
// countdown -> the engine collects the step's window -> accepted or refused (with the engine's
// reason), for the heading step, the T-pose step and the heading reset. The window only draws
// what this class says and forwards its buttons; the tests drive it against replayed captures.
//
// Time is whatever clock the caller passes to Update (seconds, monotonic): the editor passes
// EditorApplication.timeSinceStartup; the engine's own windows are measured on the session clock.

using System;
using System.Collections.Generic;
using System.Runtime.InteropServices;

namespace Mocap.Imu
{
    /// <summary>What the flow needs from a session: start a step, read its report.</summary>
    public interface ICalibrationTarget
    {
        /// <summary>Run a step from the next frame on for <paramref name="durationSeconds"/> (0.2..15).</summary>
        void BeginCalibration(CalibrationStep step, float durationSeconds);

        /// <summary>The latest request of one step: waiting, collecting or its result.</summary>
        CalibrationReport GetCalibrationReport(CalibrationStep step);
    }

    /// <summary><see cref="ICalibrationTarget"/> over a <see cref="MocapSession"/> (also one a solver consumes).</summary>
    public sealed class SessionCalibrationTarget : ICalibrationTarget
    {
        readonly MocapSession _session;

        public SessionCalibrationTarget(MocapSession session)
        {
            _session = session ?? throw new ArgumentNullException(nameof(session));
        }

        public void BeginCalibration(CalibrationStep step, float durationSeconds) =>
            _session.BeginCalibration(step, durationSeconds);

        public CalibrationReport GetCalibrationReport(CalibrationStep step) => _session.GetCalibrationReport(step);
    }

    /// <summary>Where a <see cref="CalibrationFlow"/> is.</summary>
    public enum CalibrationFlowPhase
    {
        /// <summary>Nothing started (or cancelled).</summary>
        Idle = 0,
        /// <summary>Counting down before the current step's window (the user gets into position).</summary>
        Countdown = 1,
        /// <summary>The engine is collecting the current step's window: hold still.</summary>
        Collecting = 2,
        /// <summary>The heading step was accepted; strap the sensors on, then <see cref="CalibrationFlow.Continue"/>.</summary>
        AwaitingTPose = 3,
        /// <summary>The current step was refused (<see cref="CalibrationFlow.Reason"/>); <see cref="CalibrationFlow.Retry"/> repeats it.</summary>
        Refused = 4,
        /// <summary>Every step of the flow was accepted.</summary>
        Complete = 5,
    }

    /// <summary>Timing of a <see cref="CalibrationFlow"/> (seconds). Changes apply from the next step.</summary>
    public sealed class CalibrationFlowSettings
    {
        /// <summary>Countdown before each step's window.</summary>
        public double CountdownSeconds { get; set; } = 3.0;
        /// <summary>Length of the heading window (sensors lying still).</summary>
        public float HeadingSeconds { get; set; } = 2.0f;
        /// <summary>Length of the T-pose window.</summary>
        public float TPoseSeconds { get; set; } = 2.0f;
        /// <summary>Length of the heading reset window.</summary>
        public float HeadingResetSeconds { get; set; } = 1.0f;
        /// <summary>
        /// How long after the window should have ended a result may take before the step is
        /// refused as "no result" (no frames arriving: sensors off, session stopped).
        /// </summary>
        public double ResultTimeoutSeconds { get; set; } = 5.0;
        /// <summary>Go on to the T-pose countdown as soon as the heading is accepted (no Continue).</summary>
        public bool AutoAdvance { get; set; }

        /// <summary>The window length of a step.</summary>
        public float DurationOf(CalibrationStep step) => step switch
        {
            CalibrationStep.Heading => HeadingSeconds,
            CalibrationStep.TPose => TPoseSeconds,
            _ => HeadingResetSeconds,
        };
    }

    /// <summary>
    /// The guided calibration: <see cref="StartFullCalibration"/> (heading, then T-pose) or
    /// <see cref="StartHeadingReset"/>, then <see cref="Update"/> every editor tick. Each step
    /// counts down, asks the engine to collect its window, and ends accepted or refused with the
    /// engine's reason naming the failing sensors. One thread.
    /// </summary>
    public sealed class CalibrationFlow
    {
        /// <summary>The engine's accepted window lengths (mocap_calibration_schedule).</summary>
        public const float MinWindowSeconds = 0.2f, MaxWindowSeconds = 15f;

        readonly ICalibrationTarget _target;
        readonly List<CalibrationStep> _steps = new List<CalibrationStep>();
        int _stepIndex;
        double _phaseStart;
        double _collectStart;
        float _windowSeconds;
        CalibrationReport _before;
        bool _seenInProgress;
        CalibrationReport _report;
        bool _hasReport;

        public CalibrationFlow(ICalibrationTarget target, CalibrationFlowSettings settings = null)
        {
            _target = target ?? throw new ArgumentNullException(nameof(target));
            Settings = settings ?? new CalibrationFlowSettings();
        }

        /// <summary>A flow over a session.</summary>
        public CalibrationFlow(MocapSession session, CalibrationFlowSettings settings = null)
            : this(new SessionCalibrationTarget(session), settings)
        {
        }

        /// <summary>Timing; may be changed between steps.</summary>
        public CalibrationFlowSettings Settings { get; }

        /// <summary>Where the flow is.</summary>
        public CalibrationFlowPhase Phase { get; private set; }

        /// <summary>The step counting down, collecting, refused or last accepted (meaningless when <see cref="Phase"/> is Idle).</summary>
        public CalibrationStep CurrentStep { get; private set; }

        /// <summary>The steps of the running flow, in order.</summary>
        public IReadOnlyList<CalibrationStep> Steps => _steps;

        /// <summary>Why the current step was refused (the engine's text, or what went wrong); "" otherwise.</summary>
        public string Reason { get; private set; } = string.Empty;

        /// <summary>Whole seconds left in the countdown, rounded up (3, 2, 1), for display.</summary>
        public int CountdownDisplay { get; private set; }

        /// <summary>Seconds left in the countdown.</summary>
        public double CountdownRemaining { get; private set; }

        /// <summary>0..1 through the collection window (the engine's progress).</summary>
        public float Progress { get; private set; }

        /// <summary>The latest report of the current step (per-sensor quality), once there is one.</summary>
        public bool TryGetReport(out CalibrationReport report)
        {
            report = _report;
            return _hasReport;
        }

        /// <summary>Reports of the steps accepted in this flow, in order.</summary>
        public IReadOnlyList<CalibrationReport> AcceptedReports => _accepted;
        readonly List<CalibrationReport> _accepted = new List<CalibrationReport>();

        /// <summary>A step ended (accepted or refused): the editor resets the character, saves, repaints.</summary>
        public event Action<CalibrationReport> StepFinished;

        /// <summary>The flow is counting down or collecting.</summary>
        public bool IsBusy => Phase == CalibrationFlowPhase.Countdown || Phase == CalibrationFlowPhase.Collecting;

        /// <summary>Heading (sensors lying still), then T-pose (sensors strapped on).</summary>
        public void StartFullCalibration(double now) =>
            Begin(now, CalibrationStep.Heading, CalibrationStep.TPose);

        /// <summary>Only the T-pose (the heading of this sensor set is still valid, e.g. after re-strapping).</summary>
        public void StartTPoseOnly(double now) => Begin(now, CalibrationStep.TPose);

        /// <summary>Yaw-only re-alignment against drift: stand still facing forward.</summary>
        public void StartHeadingReset(double now) => Begin(now, CalibrationStep.HeadingReset);

        /// <summary>After the heading was accepted: start the T-pose countdown.</summary>
        public void Continue(double now)
        {
            if (Phase != CalibrationFlowPhase.AwaitingTPose)
                throw new InvalidOperationException($"Continue is for after the heading step; the flow is {Phase}");
            _stepIndex++;
            StartCountdown(now);
        }

        /// <summary>After a refusal: count down and collect the same step again.</summary>
        public void Retry(double now)
        {
            if (Phase != CalibrationFlowPhase.Refused)
                throw new InvalidOperationException($"Retry is for a refused step; the flow is {Phase}");
            StartCountdown(now);
        }

        /// <summary>
        /// Stop guiding. A window the engine is already collecting still finishes there (the C API
        /// cannot cancel it) and applies if accepted; the flow just stops waiting for it.
        /// </summary>
        public void Cancel()
        {
            Phase = CalibrationFlowPhase.Idle;
            Reason = string.Empty;
            CountdownDisplay = 0;
            CountdownRemaining = 0;
        }

        /// <summary>Advance the flow to <paramref name="now"/>; true when something visible changed.</summary>
        public bool Update(double now)
        {
            switch (Phase)
            {
                case CalibrationFlowPhase.Countdown:
                    return UpdateCountdown(now);
                case CalibrationFlowPhase.Collecting:
                    return UpdateCollecting(now);
                default:
                    return false;
            }
        }

        /// <summary>What the user should do now, in one or two sentences.</summary>
        public string Instruction
        {
            get
            {
                // Cached: an overlay reads it several times per frame, and it changes only with
                // the phase, the step, the countdown's second and the refusal reason.
                int countdown = Phase == CalibrationFlowPhase.Countdown ? CountdownDisplay : 0;
                if (_instruction == null || _instructionPhase != Phase || _instructionStep != CurrentStep ||
                    _instructionCountdown != countdown || !ReferenceEquals(_instructionReason, Reason))
                {
                    _instruction = BuildInstruction();
                    _instructionPhase = Phase;
                    _instructionStep = CurrentStep;
                    _instructionCountdown = countdown;
                    _instructionReason = Reason;
                }
                return _instruction;
            }
        }

        string _instruction, _instructionReason;
        CalibrationFlowPhase _instructionPhase;
        CalibrationStep _instructionStep;
        int _instructionCountdown;

        string BuildInstruction()
        {
            switch (Phase)
            {
                case CalibrationFlowPhase.Idle:
                    return "Press Calibrate to start: first the heading step (sensors lying on a table), then the T-pose step (sensors strapped on).";
                case CalibrationFlowPhase.Countdown:
                    return Pose(CurrentStep) + $" Starting in {CountdownDisplay}...";
                case CalibrationFlowPhase.Collecting:
                    return Hold(CurrentStep);
                case CalibrationFlowPhase.AwaitingTPose:
                    return "Heading accepted. Strap the sensors on (pelvis, both wrists, both shins, head), then press Continue and stand in a T-pose.";
                case CalibrationFlowPhase.Refused:
                    return $"{StepTitle(CurrentStep)} refused: {Reason} Fix it and press Retry.";
                case CalibrationFlowPhase.Complete:
                    return CurrentStep == CalibrationStep.HeadingReset
                        ? "Heading reset accepted: every bone faces forward again."
                        : "Calibrated: every sensor has a heading and a mounting rotation.";
                default:
                    return string.Empty;
            }
        }

        /// <summary>A step's name for people.</summary>
        public static string StepTitle(CalibrationStep step) => step switch
        {
            CalibrationStep.Heading => "Heading step",
            CalibrationStep.TPose => "T-pose step",
            CalibrationStep.HeadingReset => "Heading reset",
            _ => step.ToString(),
        };

        static string Pose(CalibrationStep step) => step switch
        {
            CalibrationStep.Heading => "Lay all the sensors flat and still on a table, X axes pointing the way you will face.",
            CalibrationStep.TPose => "Stand in a T-pose facing forward: arms straight out, palms down, feet together.",
            _ => "Stand still and upright, facing forward (T-pose or arms down).",
        };

        static string Hold(CalibrationStep step) => step switch
        {
            CalibrationStep.Heading => "Collecting: do not touch the sensors.",
            CalibrationStep.TPose => "Collecting: hold the T-pose.",
            _ => "Collecting: stand still, facing forward.",
        };

        void Begin(double now, params CalibrationStep[] steps)
        {
            if (IsBusy) throw new InvalidOperationException($"a calibration is already running ({Phase}); cancel it first");
            foreach (var step in steps)
            {
                float seconds = Settings.DurationOf(step);
                if (!(seconds >= MinWindowSeconds && seconds <= MaxWindowSeconds))
                    throw new ArgumentOutOfRangeException(nameof(Settings), seconds,
                        $"{StepTitle(step)}: the window must last {MinWindowSeconds}..{MaxWindowSeconds} s");
            }
            _steps.Clear();
            _steps.AddRange(steps);
            _accepted.Clear();
            _stepIndex = 0;
            StartCountdown(now);
        }

        void StartCountdown(double now)
        {
            CurrentStep = _steps[_stepIndex];
            Phase = CalibrationFlowPhase.Countdown;
            Reason = string.Empty;
            Progress = 0;
            _hasReport = false;
            _phaseStart = now;
            SetCountdown(Math.Max(0, Settings.CountdownSeconds));
            // A zero countdown starts the window at once.
            if (CountdownRemaining <= 0) UpdateCountdown(now);
        }

        void SetCountdown(double remaining)
        {
            CountdownRemaining = remaining;
            CountdownDisplay = (int)Math.Ceiling(remaining - 1e-9);
        }

        bool UpdateCountdown(double now)
        {
            double remaining = Settings.CountdownSeconds - (now - _phaseStart);
            if (remaining > 0)
            {
                int before = CountdownDisplay;
                SetCountdown(remaining);
                return before != CountdownDisplay;
            }
            SetCountdown(0);
            float seconds = Settings.DurationOf(CurrentStep);
            try
            {
                // What the step's report said before: a finished report identical to it afterwards
                // is the previous request's result, not this one's (the engine publishes the new
                // request's state only when its processing thread takes it).
                _before = _target.GetCalibrationReport(CurrentStep);
                _target.BeginCalibration(CurrentStep, seconds);
            }
            catch (Exception e) when (e is MocapException || e is InvalidOperationException || e is ObjectDisposedException)
            {
                Refuse("the session could not start the step: " + e.Message);
                return true;
            }
            _windowSeconds = seconds;
            _collectStart = now;
            _seenInProgress = false;
            Phase = CalibrationFlowPhase.Collecting;
            return true;
        }

        bool UpdateCollecting(double now)
        {
            CalibrationReport report;
            try
            {
                report = _target.GetCalibrationReport(CurrentStep);
            }
            catch (Exception e) when (e is MocapException || e is InvalidOperationException || e is ObjectDisposedException)
            {
                Refuse("the session stopped answering: " + e.Message);
                return true;
            }

            if (report.State == CalibrationState.Waiting || report.State == CalibrationState.Collecting)
            {
                _seenInProgress = true;
                _report = report;
                _hasReport = true;
                Progress = report.State == CalibrationState.Collecting ? Clamp01(report.Progress) : 0;
                return true;
            }

            if (report.IsFinished && (_seenInProgress || !SameBytes(report, _before)))
            {
                _report = report;
                _hasReport = true;
                Progress = 1;
                if (report.State == CalibrationState.Accepted) Accept(report, now);
                else
                {
                    var reason = report.Reason;
                    Refuse(string.IsNullOrEmpty(reason) ? "the engine gave no reason" : reason);
                }
                StepFinished?.Invoke(report);
                return true;
            }

            if (now - _collectStart > _windowSeconds + Settings.ResultTimeoutSeconds)
            {
                Refuse($"no result {now - _collectStart:0.0} s after the step began: no frames are arriving " +
                       "(sensors off or out of range, or the session is not running).");
                return true;
            }
            return false;
        }

        void Accept(CalibrationReport report, double now)
        {
            _accepted.Add(report);
            Reason = string.Empty;
            bool last = _stepIndex + 1 >= _steps.Count;
            if (last)
            {
                Phase = CalibrationFlowPhase.Complete;
                return;
            }
            if (CurrentStep == CalibrationStep.Heading && !Settings.AutoAdvance)
            {
                Phase = CalibrationFlowPhase.AwaitingTPose;
                return;
            }
            _stepIndex++;
            StartCountdown(now);
        }

        void Refuse(string reason)
        {
            Phase = CalibrationFlowPhase.Refused;
            Reason = reason;
        }

        static float Clamp01(float v) => v < 0 ? 0 : v > 1 ? 1 : float.IsNaN(v) ? 0 : v;

        static bool SameBytes(CalibrationReport a, CalibrationReport b) =>
            MemoryMarshal.AsBytes(MemoryMarshal.CreateSpan(ref a, 1))
                .SequenceEqual(MemoryMarshal.AsBytes(MemoryMarshal.CreateSpan(ref b, 1)));
    }
}
