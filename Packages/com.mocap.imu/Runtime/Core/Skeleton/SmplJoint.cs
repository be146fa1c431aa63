namespace Mocap.Imu.Skeleton
{
    /// <summary>
    /// The 24 joints of the model's SMPL-topology skeleton, numbered as in the model contract
    /// (docs/model-contract.md). "Left" is the character's left.
    /// </summary>
    public enum SmplJoint
    {
        /// <summary>Root; its rotation is global, its position the pelvis.</summary>
        Pelvis = 0,
        /// <summary>Left hip (drives the left thigh).</summary>
        LeftHip = 1,
        /// <summary>Right hip.</summary>
        RightHip = 2,
        /// <summary>Lower spine.</summary>
        Spine1 = 3,
        /// <summary>Left knee (drives the shin).</summary>
        LeftKnee = 4,
        /// <summary>Right knee.</summary>
        RightKnee = 5,
        /// <summary>Middle spine.</summary>
        Spine2 = 6,
        /// <summary>Left ankle (drives the foot).</summary>
        LeftAnkle = 7,
        /// <summary>Right ankle.</summary>
        RightAnkle = 8,
        /// <summary>Upper spine.</summary>
        Spine3 = 9,
        /// <summary>Left ball of the foot (drives the toes).</summary>
        LeftFoot = 10,
        /// <summary>Right ball of the foot.</summary>
        RightFoot = 11,
        /// <summary>Neck base (C7).</summary>
        Neck = 12,
        /// <summary>Left collar bone.</summary>
        LeftCollar = 13,
        /// <summary>Right collar bone.</summary>
        RightCollar = 14,
        /// <summary>Skull base.</summary>
        Head = 15,
        /// <summary>Left glenohumeral joint (drives the upper arm).</summary>
        LeftShoulder = 16,
        /// <summary>Right glenohumeral joint.</summary>
        RightShoulder = 17,
        /// <summary>Left elbow (drives the forearm).</summary>
        LeftElbow = 18,
        /// <summary>Right elbow.</summary>
        RightElbow = 19,
        /// <summary>Left wrist (drives the hand).</summary>
        LeftWrist = 20,
        /// <summary>Right wrist.</summary>
        RightWrist = 21,
        /// <summary>Left knuckles: the end point of the hand bone.</summary>
        LeftHand = 22,
        /// <summary>Right knuckles.</summary>
        RightHand = 23,
    }
}
