// Declarations only (see ../README.md): the Unity Test Framework's editor side (test run callbacks).
using System;

namespace UnityEditor.TestTools.TestRunner.Api
{
    public enum TestMode { EditMode = 1, PlayMode = 2 }

    public partial interface ITestAdaptor
    {
        string Name { get; }
        string FullName { get; }
    }

    public partial interface ITestResultAdaptor
    {
        ITestAdaptor Test { get; }
        string ResultState { get; }
        string Message { get; }
    }

    public partial interface ICallbacks
    {
        void RunStarted(ITestAdaptor testsToRun);
        void RunFinished(ITestResultAdaptor result);
        void TestStarted(ITestAdaptor test);
        void TestFinished(ITestResultAdaptor result);
    }
}
