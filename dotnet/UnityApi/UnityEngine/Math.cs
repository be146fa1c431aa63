// Declarations only (see ../README.md): vectors, rotations, colours, rectangles.
using System;

namespace UnityEngine
{
    public partial struct Vector2 : IEquatable<Vector2>
    {
        public float x;
        public float y;
        public Vector2(float x, float y) => throw null;
        public float magnitude => throw null;
        public float sqrMagnitude => throw null;
        public Vector2 normalized => throw null;
        public static Vector2 zero => throw null;
        public static Vector2 one => throw null;
        public bool Equals(Vector2 other) => throw null;
        public override bool Equals(object other) => throw null;
        public override int GetHashCode() => throw null;
        public static Vector2 operator +(Vector2 a, Vector2 b) => throw null;
        public static Vector2 operator -(Vector2 a, Vector2 b) => throw null;
        public static Vector2 operator *(Vector2 a, float d) => throw null;
        public static Vector2 operator *(float d, Vector2 a) => throw null;
        public static Vector2 operator /(Vector2 a, float d) => throw null;
        public static bool operator ==(Vector2 lhs, Vector2 rhs) => throw null;
        public static bool operator !=(Vector2 lhs, Vector2 rhs) => throw null;
        public static implicit operator Vector2(Vector3 v) => throw null;
        public static implicit operator Vector3(Vector2 v) => throw null;
    }

    public partial struct Vector3 : IEquatable<Vector3>
    {
        public float x;
        public float y;
        public float z;
        public Vector3(float x, float y, float z) => throw null;
        public Vector3(float x, float y) => throw null;
        public float this[int index] { get => throw null; set => throw null; }
        public float magnitude => throw null;
        public float sqrMagnitude => throw null;
        public Vector3 normalized => throw null;
        public void Normalize() => throw null;
        public void Set(float newX, float newY, float newZ) => throw null;
        public static Vector3 zero => throw null;
        public static Vector3 one => throw null;
        public static Vector3 up => throw null;
        public static Vector3 down => throw null;
        public static Vector3 left => throw null;
        public static Vector3 right => throw null;
        public static Vector3 forward => throw null;
        public static Vector3 back => throw null;
        public static float Dot(Vector3 lhs, Vector3 rhs) => throw null;
        public static Vector3 Cross(Vector3 lhs, Vector3 rhs) => throw null;
        public static float Distance(Vector3 a, Vector3 b) => throw null;
        public static float Angle(Vector3 from, Vector3 to) => throw null;
        public static Vector3 Lerp(Vector3 a, Vector3 b, float t) => throw null;
        public static Vector3 Scale(Vector3 a, Vector3 b) => throw null;
        public static Vector3 ClampMagnitude(Vector3 vector, float maxLength) => throw null;
        public static Vector3 Project(Vector3 vector, Vector3 onNormal) => throw null;
        public static Vector3 ProjectOnPlane(Vector3 vector, Vector3 planeNormal) => throw null;
        public static Vector3 Min(Vector3 lhs, Vector3 rhs) => throw null;
        public static Vector3 Max(Vector3 lhs, Vector3 rhs) => throw null;
        public bool Equals(Vector3 other) => throw null;
        public override bool Equals(object other) => throw null;
        public override int GetHashCode() => throw null;
        public override string ToString() => throw null;
        public string ToString(string format) => throw null;
        public static Vector3 operator +(Vector3 a, Vector3 b) => throw null;
        public static Vector3 operator -(Vector3 a, Vector3 b) => throw null;
        public static Vector3 operator -(Vector3 a) => throw null;
        public static Vector3 operator *(Vector3 a, float d) => throw null;
        public static Vector3 operator *(float d, Vector3 a) => throw null;
        public static Vector3 operator /(Vector3 a, float d) => throw null;
        public static bool operator ==(Vector3 lhs, Vector3 rhs) => throw null;
        public static bool operator !=(Vector3 lhs, Vector3 rhs) => throw null;
    }

    public partial struct Vector4 : IEquatable<Vector4>
    {
        public float x;
        public float y;
        public float z;
        public float w;
        public Vector4(float x, float y, float z, float w) => throw null;
        public bool Equals(Vector4 other) => throw null;
        public override bool Equals(object other) => throw null;
        public override int GetHashCode() => throw null;
    }

    public partial struct Quaternion : IEquatable<Quaternion>
    {
        public float x;
        public float y;
        public float z;
        public float w;
        public Quaternion(float x, float y, float z, float w) => throw null;
        public static Quaternion identity => throw null;
        public Vector3 eulerAngles { get => throw null; set => throw null; }
        public Quaternion normalized => throw null;
        public void ToAngleAxis(out float angle, out Vector3 axis) => throw null;
        public static Quaternion Euler(float x, float y, float z) => throw null;
        public static Quaternion Euler(Vector3 euler) => throw null;
        public static Quaternion AngleAxis(float angle, Vector3 axis) => throw null;
        public static Quaternion LookRotation(Vector3 forward) => throw null;
        public static Quaternion LookRotation(Vector3 forward, Vector3 upwards) => throw null;
        public static Quaternion FromToRotation(Vector3 fromDirection, Vector3 toDirection) => throw null;
        public static Quaternion Inverse(Quaternion rotation) => throw null;
        public static Quaternion Slerp(Quaternion a, Quaternion b, float t) => throw null;
        public static Quaternion Lerp(Quaternion a, Quaternion b, float t) => throw null;
        public static Quaternion RotateTowards(Quaternion from, Quaternion to, float maxDegreesDelta) => throw null;
        public static Quaternion Normalize(Quaternion q) => throw null;
        public static float Angle(Quaternion a, Quaternion b) => throw null;
        public static float Dot(Quaternion a, Quaternion b) => throw null;
        public bool Equals(Quaternion other) => throw null;
        public override bool Equals(object other) => throw null;
        public override int GetHashCode() => throw null;
        public override string ToString() => throw null;
        public static Quaternion operator *(Quaternion lhs, Quaternion rhs) => throw null;
        public static Vector3 operator *(Quaternion rotation, Vector3 point) => throw null;
        public static bool operator ==(Quaternion lhs, Quaternion rhs) => throw null;
        public static bool operator !=(Quaternion lhs, Quaternion rhs) => throw null;
    }

    public partial struct Matrix4x4 : IEquatable<Matrix4x4>
    {
        public static Matrix4x4 identity => throw null;
        public static Matrix4x4 TRS(Vector3 pos, Quaternion q, Vector3 s) => throw null;
        public static Matrix4x4 Scale(Vector3 vector) => throw null;
        public Vector3 MultiplyPoint(Vector3 point) => throw null;
        public Vector3 MultiplyPoint3x4(Vector3 point) => throw null;
        public Vector3 MultiplyVector(Vector3 vector) => throw null;
        public Matrix4x4 inverse => throw null;
        public bool Equals(Matrix4x4 other) => throw null;
        public override bool Equals(object other) => throw null;
        public override int GetHashCode() => throw null;
        public static Matrix4x4 operator *(Matrix4x4 lhs, Matrix4x4 rhs) => throw null;
    }

    public partial struct Color : IEquatable<Color>
    {
        public float r;
        public float g;
        public float b;
        public float a;
        public Color(float r, float g, float b) => throw null;
        public Color(float r, float g, float b, float a) => throw null;
        public static Color red => throw null;
        public static Color green => throw null;
        public static Color blue => throw null;
        public static Color white => throw null;
        public static Color black => throw null;
        public static Color yellow => throw null;
        public static Color cyan => throw null;
        public static Color magenta => throw null;
        public static Color gray => throw null;
        public static Color grey => throw null;
        public static Color clear => throw null;
        public static Color Lerp(Color a, Color b, float t) => throw null;
        public bool Equals(Color other) => throw null;
        public override bool Equals(object other) => throw null;
        public override int GetHashCode() => throw null;
        public static Color operator *(Color a, float b) => throw null;
        public static bool operator ==(Color lhs, Color rhs) => throw null;
        public static bool operator !=(Color lhs, Color rhs) => throw null;
    }

    public partial struct Color32
    {
        public byte r;
        public byte g;
        public byte b;
        public byte a;
        public Color32(byte r, byte g, byte b, byte a) => throw null;
    }

    public partial struct Rect : IEquatable<Rect>
    {
        public Rect(float x, float y, float width, float height) => throw null;
        public Rect(Vector2 position, Vector2 size) => throw null;
        public float x { get => throw null; set => throw null; }
        public float y { get => throw null; set => throw null; }
        public float width { get => throw null; set => throw null; }
        public float height { get => throw null; set => throw null; }
        public float xMin { get => throw null; set => throw null; }
        public float yMin { get => throw null; set => throw null; }
        public float xMax { get => throw null; set => throw null; }
        public float yMax { get => throw null; set => throw null; }
        public Vector2 position { get => throw null; set => throw null; }
        public Vector2 size { get => throw null; set => throw null; }
        public Vector2 center { get => throw null; set => throw null; }
        public bool Contains(Vector2 point) => throw null;
        public bool Equals(Rect other) => throw null;
        public override bool Equals(object other) => throw null;
        public override int GetHashCode() => throw null;
        public static bool operator ==(Rect lhs, Rect rhs) => throw null;
        public static bool operator !=(Rect lhs, Rect rhs) => throw null;
    }

    public partial struct Mathf
    {
        public const float PI = 3.14159274F;
        public const float Infinity = float.PositiveInfinity;
        public const float NegativeInfinity = float.NegativeInfinity;
        public const float Deg2Rad = 0.0174532924F;
        public const float Rad2Deg = 57.29578F;
        public static readonly float Epsilon;
        public static float Abs(float f) => throw null;
        public static int Abs(int value) => throw null;
        public static float Min(float a, float b) => throw null;
        public static float Min(params float[] values) => throw null;
        public static int Min(int a, int b) => throw null;
        public static float Max(float a, float b) => throw null;
        public static float Max(params float[] values) => throw null;
        public static int Max(int a, int b) => throw null;
        public static float Clamp(float value, float min, float max) => throw null;
        public static int Clamp(int value, int min, int max) => throw null;
        public static float Clamp01(float value) => throw null;
        public static float Lerp(float a, float b, float t) => throw null;
        public static float InverseLerp(float a, float b, float value) => throw null;
        public static float Sqrt(float f) => throw null;
        public static float Sin(float f) => throw null;
        public static float Cos(float f) => throw null;
        public static float Atan2(float y, float x) => throw null;
        public static float Round(float f) => throw null;
        public static int RoundToInt(float f) => throw null;
        public static int FloorToInt(float f) => throw null;
        public static int CeilToInt(float f) => throw null;
        public static float Repeat(float t, float length) => throw null;
        public static float DeltaAngle(float current, float target) => throw null;
        public static bool Approximately(float a, float b) => throw null;
        public static float MoveTowards(float current, float target, float maxDelta) => throw null;
        public static float SmoothDamp(float current, float target, ref float currentVelocity, float smoothTime) => throw null;
    }
}
