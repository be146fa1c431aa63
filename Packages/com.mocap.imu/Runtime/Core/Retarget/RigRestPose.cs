namespace Mocap.Imu.Retarget
{
    /// <summary>What a rig's described rest pose is, which decides the pose the SMPL rest (identity) maps to.</summary>
    public enum RigRestPose
    {
        /// <summary>
        /// The described rest is the rig's T-pose (e.g. read from the Avatar's T-pose skeleton). The
        /// SMPL rest reproduces it exactly, including the rig's own small deviations from SMPL's
        /// proportions (a curved spine stays curved).
        /// </summary>
        TPose,

        /// <summary>
        /// The described rest is any bind pose (A-pose, arms forward, legs apart). The T-pose is
        /// derived by turning each bone, parents first, by the smallest rotation that points it along
        /// the SMPL T-pose direction (Hips: its hip line and its hips-to-head line); bones without a
        /// child to point at (hands, head, toes) follow their parent's correction.
        /// </summary>
        AlignToSmplTPose,
    }
}
