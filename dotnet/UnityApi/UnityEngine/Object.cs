// Declarations only (see ../README.md): members of UnityEngine's core object model.
using System;
using System.Collections;

namespace UnityEngine
{
    public enum FindObjectsSortMode { None = 0, InstanceID = 1 }
    public enum FindObjectsInactive { Exclude = 0, Include = 1 }
    public enum HideFlags { None = 0, HideInHierarchy = 1, HideInInspector = 2, DontSaveInEditor = 4, NotEditable = 8, DontSaveInBuild = 16, DontUnloadUnusedAsset = 32, DontSave = 52, HideAndDontSave = 61 }
    public enum SendMessageOptions { RequireReceiver = 0, DontRequireReceiver = 1 }

    public partial class Object
    {
        public string name { get => throw null; set => throw null; }
        public HideFlags hideFlags { get => throw null; set => throw null; }
        public int GetInstanceID() => throw null;
        public override bool Equals(object other) => throw null;
        public override int GetHashCode() => throw null;
        public override string ToString() => throw null;
        public static implicit operator bool(Object exists) => throw null;
        public static bool operator ==(Object x, Object y) => throw null;
        public static bool operator !=(Object x, Object y) => throw null;

        public static void Destroy(Object obj) => throw null;
        public static void Destroy(Object obj, float t) => throw null;
        public static void DestroyImmediate(Object obj) => throw null;
        public static void DestroyImmediate(Object obj, bool allowDestroyingAssets) => throw null;
        public static void DontDestroyOnLoad(Object target) => throw null;
        public static T Instantiate<T>(T original) where T : Object => throw null;
        public static T Instantiate<T>(T original, Transform parent) where T : Object => throw null;
        public static T Instantiate<T>(T original, Vector3 position, Quaternion rotation) where T : Object => throw null;
        public static Object Instantiate(Object original) => throw null;

#if UNITY_6000_0_OR_NEWER
        [Obsolete("Object.FindObjectOfType has been deprecated. Use Object.FindFirstObjectByType if you need the first object, or FindAnyObjectByType if any object is acceptable.")]
#endif
        public static T FindObjectOfType<T>() where T : Object => throw null;
#if UNITY_6000_0_OR_NEWER
        [Obsolete("Object.FindObjectOfType has been deprecated. Use Object.FindFirstObjectByType if you need the first object, or FindAnyObjectByType if any object is acceptable.")]
#endif
        public static T FindObjectOfType<T>(bool includeInactive) where T : Object => throw null;
#if UNITY_6000_0_OR_NEWER
        [Obsolete("Object.FindObjectOfType has been deprecated. Use Object.FindFirstObjectByType if you need the first object, or FindAnyObjectByType if any object is acceptable.")]
#endif
        public static Object FindObjectOfType(Type type) => throw null;
#if UNITY_6000_0_OR_NEWER
        [Obsolete("Object.FindObjectsOfType has been deprecated. Use Object.FindObjectsByType instead which lets you decide whether you need the results sorted or not.")]
#endif
        public static T[] FindObjectsOfType<T>() where T : Object => throw null;
#if UNITY_6000_0_OR_NEWER
        [Obsolete("Object.FindObjectsOfType has been deprecated. Use Object.FindObjectsByType instead which lets you decide whether you need the results sorted or not.")]
#endif
        public static T[] FindObjectsOfType<T>(bool includeInactive) where T : Object => throw null;
#if UNITY_6000_0_OR_NEWER
        [Obsolete("Object.FindObjectsOfType has been deprecated. Use Object.FindObjectsByType instead which lets you decide whether you need the results sorted or not.")]
#endif
        public static Object[] FindObjectsOfType(Type type) => throw null;

        public static T[] FindObjectsByType<T>(FindObjectsSortMode sortMode) where T : Object => throw null;
        public static T[] FindObjectsByType<T>(FindObjectsInactive findObjectsInactive, FindObjectsSortMode sortMode) where T : Object => throw null;
        public static Object[] FindObjectsByType(Type type, FindObjectsSortMode sortMode) => throw null;
        public static T FindAnyObjectByType<T>() where T : Object => throw null;
        public static T FindAnyObjectByType<T>(FindObjectsInactive findObjectsInactive) where T : Object => throw null;
        public static T FindFirstObjectByType<T>() where T : Object => throw null;
        public static T FindFirstObjectByType<T>(FindObjectsInactive findObjectsInactive) where T : Object => throw null;
    }

    public partial class Component : Object
    {
        public Transform transform => throw null;
        public GameObject gameObject => throw null;
        public string tag { get => throw null; set => throw null; }
        public T GetComponent<T>() => throw null;
        public Component GetComponent(Type type) => throw null;
        public bool TryGetComponent<T>(out T component) => throw null;
        public T GetComponentInChildren<T>() => throw null;
        public T GetComponentInChildren<T>(bool includeInactive) => throw null;
        public T[] GetComponentsInChildren<T>() => throw null;
        public T[] GetComponentsInChildren<T>(bool includeInactive) => throw null;
        public T GetComponentInParent<T>() => throw null;
        public T[] GetComponents<T>() => throw null;
        public bool CompareTag(string tag) => throw null;
    }

    public partial class Behaviour : Component
    {
        public bool enabled { get => throw null; set => throw null; }
        public bool isActiveAndEnabled => throw null;
    }

    public partial class Coroutine { }
    public partial class YieldInstruction { }
    public sealed partial class WaitForEndOfFrame : YieldInstruction { }
    public sealed partial class WaitForFixedUpdate : YieldInstruction { }
    public sealed partial class WaitForSeconds : YieldInstruction { public WaitForSeconds(float seconds) => throw null; }
    public partial class WaitForSecondsRealtime : CustomYieldInstruction
    {
        public WaitForSecondsRealtime(float time) => throw null;
        public override bool keepWaiting => throw null;
    }
    public abstract partial class CustomYieldInstruction : IEnumerator
    {
        public abstract bool keepWaiting { get; }
        public object Current => throw null;
        public bool MoveNext() => throw null;
        public virtual void Reset() => throw null;
    }
    public sealed partial class WaitUntil : CustomYieldInstruction
    {
        public WaitUntil(Func<bool> predicate) => throw null;
        public override bool keepWaiting => throw null;
    }

    public partial class MonoBehaviour : Behaviour
    {
        public bool useGUILayout { get => throw null; set => throw null; }
        public Coroutine StartCoroutine(IEnumerator routine) => throw null;
        public void StopCoroutine(Coroutine routine) => throw null;
        public void StopAllCoroutines() => throw null;
        public void Invoke(string methodName, float time) => throw null;
        public static void print(object message) => throw null;
    }

    public partial class ScriptableObject : Object
    {
        public static T CreateInstance<T>() where T : ScriptableObject => throw null;
        public static ScriptableObject CreateInstance(Type type) => throw null;
    }

    public sealed partial class GameObject : Object
    {
        public GameObject() => throw null;
        public GameObject(string name) => throw null;
        public GameObject(string name, params Type[] components) => throw null;
        public Transform transform => throw null;
        public GameObject gameObject => throw null;
        public bool activeSelf => throw null;
        public bool activeInHierarchy => throw null;
        public int layer { get => throw null; set => throw null; }
        public string tag { get => throw null; set => throw null; }
        public void SetActive(bool value) => throw null;
        public T AddComponent<T>() where T : Component => throw null;
        public Component AddComponent(Type componentType) => throw null;
        public T GetComponent<T>() => throw null;
        public Component GetComponent(Type type) => throw null;
        public bool TryGetComponent<T>(out T component) => throw null;
        public T GetComponentInChildren<T>() => throw null;
        public T GetComponentInChildren<T>(bool includeInactive) => throw null;
        public T[] GetComponentsInChildren<T>() => throw null;
        public T[] GetComponentsInChildren<T>(bool includeInactive) => throw null;
        public T[] GetComponents<T>() => throw null;
        public T GetComponentInParent<T>() => throw null;
        public bool CompareTag(string tag) => throw null;
        public static GameObject CreatePrimitive(PrimitiveType type) => throw null;
        public static GameObject Find(string name) => throw null;
    }

    public partial class Transform : Component, IEnumerable
    {
        protected Transform() => throw null;
        public Vector3 position { get => throw null; set => throw null; }
        public Vector3 localPosition { get => throw null; set => throw null; }
        public Quaternion rotation { get => throw null; set => throw null; }
        public Quaternion localRotation { get => throw null; set => throw null; }
        public Vector3 eulerAngles { get => throw null; set => throw null; }
        public Vector3 localEulerAngles { get => throw null; set => throw null; }
        public Vector3 localScale { get => throw null; set => throw null; }
        public Vector3 lossyScale => throw null;
        public Vector3 forward { get => throw null; set => throw null; }
        public Vector3 up { get => throw null; set => throw null; }
        public Vector3 right { get => throw null; set => throw null; }
        public Transform parent { get => throw null; set => throw null; }
        public Transform root => throw null;
        public int childCount => throw null;
        public Matrix4x4 localToWorldMatrix => throw null;
        public Matrix4x4 worldToLocalMatrix => throw null;
        public void SetParent(Transform parent) => throw null;
        public void SetParent(Transform parent, bool worldPositionStays) => throw null;
        public void SetPositionAndRotation(Vector3 position, Quaternion rotation) => throw null;
        public void SetLocalPositionAndRotation(Vector3 localPosition, Quaternion localRotation) => throw null;
        public void GetPositionAndRotation(out Vector3 position, out Quaternion rotation) => throw null;
        public void GetLocalPositionAndRotation(out Vector3 localPosition, out Quaternion localRotation) => throw null;
        public Transform GetChild(int index) => throw null;
        public Transform Find(string n) => throw null;
        public bool IsChildOf(Transform parent) => throw null;
        public void LookAt(Transform target) => throw null;
        public void LookAt(Vector3 worldPosition) => throw null;
        public void LookAt(Vector3 worldPosition, Vector3 worldUp) => throw null;
        public void Rotate(Vector3 eulers) => throw null;
        public void Translate(Vector3 translation) => throw null;
        public Vector3 TransformPoint(Vector3 position) => throw null;
        public Vector3 InverseTransformPoint(Vector3 position) => throw null;
        public Vector3 TransformDirection(Vector3 direction) => throw null;
        public Vector3 InverseTransformDirection(Vector3 direction) => throw null;
        public Vector3 TransformVector(Vector3 vector) => throw null;
        public Vector3 InverseTransformVector(Vector3 vector) => throw null;
        public IEnumerator GetEnumerator() => throw null;
    }
}
