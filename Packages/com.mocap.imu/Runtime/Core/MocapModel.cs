using System;
using System.Collections.Generic;
using Mocap.Imu.Maths;
using Mocap.Imu.Skeleton;

namespace Mocap.Imu
{
    /// <summary>Where the model runs (mocap_execution_provider).</summary>
    public enum ExecutionProvider
    {
        /// <summary>ONNX Runtime's CPU provider (always available).</summary>
        Cpu = 0,
        /// <summary>NVIDIA CUDA: needs a CUDA build of ONNX Runtime and a GPU; refused clearly otherwise.</summary>
        Cuda = 1,
    }

    /// <summary>ONNX Runtime graph optimisation level.</summary>
    public enum GraphOptimizationLevel
    {
        None = 0,
        Basic = 1,
        Extended = 2,
        /// <summary>Every optimisation (the engine's default).</summary>
        All = 3,
    }

    /// <summary>
    /// How to load a pose model (mocap_model_options). A new instance holds the engine's defaults:
    /// CPU, one ONNX Runtime thread, every optimisation, the ONNX Runtime library found by the
    /// engine ($MOCAP_ONNXRUNTIME_PATH, then the path compiled in).
    /// </summary>
    public sealed class ModelOptions
    {
        /// <summary>CPU or CUDA.</summary>
        public ExecutionProvider ExecutionProvider { get; set; } = ExecutionProvider.Cpu;
        /// <summary>Threads ONNX Runtime uses inside one operator: 1 (the default) runs the model
        /// on the solver's thread; 0 = ONNX Runtime's own default, a thread per core whose idle
        /// threads spin (a whole core busy while a session runs, for no faster frame).</summary>
        public int IntraOpThreads { get; set; } = 1;
        /// <summary>Graph optimisation level.</summary>
        public GraphOptimizationLevel OptimizationLevel { get; set; } = GraphOptimizationLevel.All;
        /// <summary>CUDA only: the device index.</summary>
        public int CudaDevice { get; set; }
        /// <summary>The ONNX Runtime shared library to load; empty = let the engine search.</summary>
        public string OnnxRuntimePath { get; set; } = string.Empty;

        internal unsafe void ToNative(out NativeModelOptions native)
        {
            fixed (NativeModelOptions* p = &native)
                NativeMethods.Check(NativeSolverMethods.mocap_model_options_defaults(p));
            native.ExecutionProvider = (int)ExecutionProvider;
            native.IntraOpThreads = IntraOpThreads;
            native.OptimizationLevel = (int)OptimizationLevel;
            native.CudaDevice = CudaDevice;
            fixed (byte* path = native.OnnxRuntimePath)
                NativeText.ToBuffer(OnnxRuntimePath, path, NativeMethods.PathMax, nameof(OnnxRuntimePath));
        }
    }

    /// <summary>One input sensor of a pose model: the segment it rides on and whether the model needs it.</summary>
    public readonly struct ModelSensor
    {
        public ModelSensor(MocapSegment segment, bool required)
        {
            Segment = segment;
            Required = required;
        }

        /// <summary>The body segment.</summary>
        public MocapSegment Segment { get; }
        /// <summary>The model needs it; an optional one may be missing (masked out).</summary>
        public bool Required { get; }

        public override string ToString() => SegmentTable.SnakeName(Segment) + (Required ? "" : " (optional)");
    }

    /// <summary>What a model's metadata says (mocap_model_info), validated by the engine at load.</summary>
    public sealed class ModelInfo
    {
        internal unsafe ModelInfo(in NativeModelInfo native, float trainingHeight = 0f, float strideExponent = 0f)
        {
            TrainingHeight = trainingHeight;
            StrideExponent = strideExponent;
            const int J = NativeSolverMethods.JointCount;
            var names = new string[J];
            var parents = new int[J];
            var offsets = new Vec3[J];
            fixed (NativeModelInfo* n = &native)
            {
                ContractVersion = n->ContractVersion;
                int sensorCount = (int)Math.Min(n->SensorCount, (uint)MocapSession.MaxSensors);
                var sensors = new ModelSensor[sensorCount];
                for (int k = 0; k < sensorCount; k++)
                    sensors[k] = new ModelSensor((MocapSegment)n->SensorSegments[k],
                                                 (n->SensorRequiredMask & (1u << k)) != 0);
                Sensors = sensors;
                FrameRate = n->FrameRate;
                StateLayers = n->StateLayers;
                StateSize = n->StateSize;
                for (int j = 0; j < J; j++)
                {
                    names[j] = NativeText.FromBuffer(n->JointNames + 32 * j, 32);
                    parents[j] = n->JointParents[j];
                    offsets[j] = new Vec3(n->RestOffsets[3 * j], n->RestOffsets[3 * j + 1], n->RestOffsets[3 * j + 2]);
                }
                Precision = NativeText.FromBuffer(n->Precision, 8);
                ModelName = NativeText.FromBuffer(n->ModelName, 128);
            }
            JointNames = names;
            JointParents = parents;
            RestOffsets = offsets;
            Skeleton = BuildSkeleton(names, parents, offsets);
        }

        /// <summary>Model contract version (docs/model-contract.md): 1 = the six fixed sensors, 2 = its own set with a mask.</summary>
        public int ContractVersion { get; }
        /// <summary>The model's input sensors, in its input order.</summary>
        public IReadOnlyList<ModelSensor> Sensors { get; }

        /// <summary>The index of the model's sensor on <paramref name="segment"/>, or -1 when it has none.</summary>
        public int IndexOf(MocapSegment segment)
        {
            for (int k = 0; k < Sensors.Count; k++)
                if (Sensors[k].Segment == segment) return k;
            return -1;
        }
        /// <summary>Frames per second the model expects; sessions feeding it must output this rate.</summary>
        public float FrameRate { get; }
        /// <summary>Recurrent state layers.</summary>
        public int StateLayers { get; }
        /// <summary>Recurrent state size per layer.</summary>
        public int StateSize { get; }
        /// <summary>Weights' precision: "fp32" or "fp16".</summary>
        public string Precision { get; }
        /// <summary>The model's own name (e.g. its training run).</summary>
        public string ModelName { get; }
        /// <summary>Joint names as the metadata gives them.</summary>
        public IReadOnlyList<string> JointNames { get; }
        /// <summary>Parent of each joint, -1 for the root.</summary>
        public IReadOnlyList<int> JointParents { get; }
        /// <summary>Rest offsets, model frame, metres; [0] is the pelvis position at rest.</summary>
        public IReadOnlyList<Vec3> RestOffsets { get; }
        /// <summary>The model's skeleton (its proportions) with forward kinematics.</summary>
        public SmplSkeleton Skeleton { get; }

        /// <summary>
        /// Standing height (metres) of the body the model learned; 0 when the model has no stride
        /// scaling and therefore takes no performer height (<see cref="MocapSolver.SetCharacterHeight"/>).
        /// </summary>
        public float TrainingHeight { get; }

        /// <summary>
        /// How the model's root speed follows the performer's size: someone S = height /
        /// <see cref="TrainingHeight"/> times that size moves about S^e times as fast as it
        /// predicts. 0 without stride scaling.
        /// </summary>
        public float StrideExponent { get; }

        /// <summary>Whether the model takes a performer height (its metadata gives the two above).</summary>
        public bool HasStrideScaling => TrainingHeight > 0f;

        static SmplSkeleton BuildSkeleton(string[] names, int[] parents, Vec3[] offsets)
        {
            // SmplSkeleton fixes names and parents to the contract; a model whose metadata differs
            // would animate the wrong bones, so say which joint differs instead of guessing.
            for (int j = 0; j < names.Length; j++)
            {
                if (names[j] != SmplSkeleton.NameOf(j))
                    throw new MocapException(MocapStatus.Format,
                        $"model joint {j} is '{names[j]}', the contract expects '{SmplSkeleton.NameOf(j)}'");
                if (parents[j] != SmplSkeleton.ParentOf(j))
                    throw new MocapException(MocapStatus.Format,
                        $"model joint {j} ({names[j]}) has parent {parents[j]}, the contract expects {SmplSkeleton.ParentOf(j)}");
            }
            try
            {
                return SmplSkeleton.FromRestOffsets(offsets);
            }
            catch (ArgumentException e)
            {
                throw new MocapException(MocapStatus.Format, "model rest offsets: " + e.Message, e);
            }
        }
    }

    /// <summary>
    /// A loaded pose model (an .onnx file meeting the model contract) with its ONNX Runtime
    /// session. One model serves any number of <see cref="MocapSolver"/>s and characters.
    /// </summary>
    /// <remarks>
    /// Disposing the model while a solver still uses it is safe: the native model is freed when
    /// the last solver built on it closes.
    /// </remarks>
    public sealed class MocapModel : IDisposable
    {
        readonly ModelHandle _handle;
        // SafeHandle.IsClosed stays false while a solver still holds a reference, so disposal of
        // this object is tracked here.
        bool _disposed;

        MocapModel(string path, ModelHandle handle, ModelInfo info)
        {
            Path = path;
            _handle = handle;
            Info = info;
        }

        /// <summary>
        /// Load and validate a model. A wrong model is refused with what differs; the process
        /// stays usable.
        /// </summary>
        /// <exception cref="MocapException">The engine's text, naming the file: not found, not a
        /// contract model, ONNX Runtime missing, or the execution provider unavailable.</exception>
        public static unsafe MocapModel Open(string path, ModelOptions options = null)
        {
            if (path == null) throw new ArgumentNullException(nameof(path));
            MocapEngine.EnsureCompatible();
            (options ?? new ModelOptions()).ToNative(out var native);
            byte[] utf8 = NativeText.ToNullTerminated(path, nameof(path));
            IntPtr model;
            MocapStatus status;
            fixed (byte* p = utf8)
                status = NativeSolverMethods.mocap_model_open(p, &native, out model);
            if (status != MocapStatus.Ok) throw NativeMethods.Failure(status);
            var handle = new ModelHandle(model);
            try
            {
                NativeModelInfo info;
                NativeMethods.Check(NativeSolverMethods.mocap_model_get_info(handle, &info));
                float height = 0f, exponent = 0f;
                MocapStatus scaling = NativeSolverMethods.mocap_model_get_stride_scaling(handle, &height, &exponent);
                if (scaling != MocapStatus.Unsupported) NativeMethods.Check(scaling); // unsupported: both stay 0
                return new MocapModel(path, handle, new ModelInfo(in info, height, exponent));
            }
            catch
            {
                handle.Dispose();
                throw;
            }
        }

        /// <summary>The file the model was loaded from.</summary>
        public string Path { get; }

        /// <summary>Frame rate, skeleton, precision and name from the model's metadata.</summary>
        public ModelInfo Info { get; }

        /// <summary>Whether <see cref="Dispose"/> has been called.</summary>
        public bool IsDisposed => _disposed;

        internal ModelHandle Handle
        {
            get
            {
                if (_disposed) throw new ObjectDisposedException(nameof(MocapModel), Path);
                return _handle;
            }
        }

        /// <summary>Release the model (deferred until solvers built on it have closed).</summary>
        public void Dispose()
        {
            _disposed = true;
            _handle.Dispose();
        }
    }
}
