// File access shared by the recording readers and writers of the core.
//
// Readers: every failure to open or read becomes a MocapException naming the file and the cause,
// with the engine's statuses (a missing file or folder NotFound, access refused Permission,
// anything else IO), never a bare IOException or UnauthorizedAccessException.
//
// Writers replace a file, never rewrite it in place: the new content goes to a unique temporary
// file next to the target, which replaces the target only after everything was written and
// flushed to disk. A failure part way (full disk, an exception) leaves the previous file as it was
// and removes the temporary, as CalibrationData.Save does in the engine.

using System;
using System.IO;
using System.Text;

namespace Mocap.Imu.Recording
{
    internal static class RecordingFiles
    {
        /// <summary>All lines of a text file.</summary>
        /// <exception cref="MocapException">The file cannot be opened or read (NotFound, Permission, IO).</exception>
        internal static string[] ReadAllLines(string path, string what)
        {
            if (path == null) throw new ArgumentNullException(nameof(path));
            try
            {
                return File.ReadAllLines(path);
            }
            catch (Exception e) when (IsFileError(e))
            {
                throw Failure(path, what, "cannot read", e);
            }
        }

        /// <summary>A file opened for reading (shared with a writer still appending).</summary>
        /// <exception cref="MocapException">The file cannot be opened (NotFound, Permission, IO).</exception>
        internal static FileStream OpenRead(string path, string what, FileShare share = FileShare.ReadWrite)
        {
            if (path == null) throw new ArgumentNullException(nameof(path));
            try
            {
                return new FileStream(path, FileMode.Open, FileAccess.Read, share);
            }
            catch (Exception e) when (IsFileError(e))
            {
                throw Failure(path, what, "cannot open", e);
            }
        }

        /// <summary>Exceptions of the file system (as opposed to bad arguments or bugs).</summary>
        internal static bool IsFileError(Exception e) =>
            e is IOException || e is UnauthorizedAccessException || e is NotSupportedException;

        /// <summary>
        /// "{what} {path}: {action}: {cause}" with the status the engine uses for the same cause:
        /// NotFound for a missing file or folder, Permission for refused access, IO otherwise.
        /// </summary>
        internal static MocapException Failure(string path, string what, string action, Exception e)
        {
            MocapStatus status;
            string cause;
            if (e is FileNotFoundException)
            {
                status = MocapStatus.NotFound;
                cause = "no such file";
            }
            else if (e is DirectoryNotFoundException)
            {
                status = MocapStatus.NotFound;
                cause = "no such directory";
            }
            else if (Directory.Exists(path))
            {
                // Opening a folder as a file: UnauthorizedAccessException on Linux and Windows,
                // which is not a permission problem.
                status = MocapStatus.IO;
                cause = "it is a directory, not a file";
            }
            else if (e is UnauthorizedAccessException)
            {
                status = MocapStatus.Permission;
                cause = "permission denied (" + e.Message + ")";
            }
            else
            {
                status = MocapStatus.IO;
                cause = e.Message;
            }
            return new MocapException(status, $"{what} {path}: {action}: {cause}", e);
        }

        /// <summary>
        /// Write <paramref name="path"/> through <paramref name="write"/> into a temporary file next
        /// to it, then replace the file with it. When <paramref name="write"/> throws, or writing,
        /// flushing or replacing fails, the previous file is unchanged and the temporary is gone.
        /// </summary>
        /// <exception cref="MocapException">Creating, writing or replacing failed (the text names <paramref name="path"/>).</exception>
        internal static void WriteReplacing(string path, string what, Action<FileStream> write)
        {
            if (path == null) throw new ArgumentNullException(nameof(path));
            if (path.Length == 0) throw new ArgumentException($"the {what} path is empty", nameof(path));
            string temporary = TemporaryPathFor(path);
            FileStream stream;
            try
            {
                stream = new FileStream(temporary, FileMode.CreateNew, FileAccess.Write, FileShare.None);
            }
            catch (Exception e) when (IsFileError(e))
            {
                throw Failure(path, what, "cannot create a temporary file beside it", e);
            }
            bool replaced = false;
            try
            {
                try
                {
                    write(stream);
                    stream.Flush(flushToDisk: true);
                }
                catch
                {
                    // The first failure is the one to report, not a second one of closing.
                    DisposeQuietly(stream);
                    throw;
                }
                stream.Dispose();
                Replace(temporary, path, what, syncFirst: false);
                replaced = true;
            }
            catch (Exception e) when (IsFileError(e))
            {
                throw Failure(path, what, "cannot write", e);
            }
            finally
            {
                if (!replaced) DeleteQuietly(temporary);
            }
        }

        /// <summary>
        /// A new name for a temporary file in the folder of <paramref name="path"/> (".NAME.RANDOM.tmp",
        /// or a shorter "~RANDOM" when that would exceed <paramref name="maxUtf8Bytes"/>).
        /// </summary>
        internal static string TemporaryPathFor(string path, int maxUtf8Bytes = int.MaxValue)
        {
            string folder = Path.GetDirectoryName(path) ?? string.Empty;
            string name = Path.GetFileName(path);
            string random = Guid.NewGuid().ToString("N").Substring(0, 8);
            string temporary = Path.Combine(folder, "." + name + "." + random + ".tmp");
            if (Encoding.UTF8.GetByteCount(temporary) > maxUtf8Bytes)
                temporary = Path.Combine(folder, "~" + random);
            return temporary;
        }

        /// <summary>
        /// Replace <paramref name="path"/> (or create it) with the complete file
        /// <paramref name="temporary"/>; on failure the temporary is deleted and the target unchanged.
        /// </summary>
        internal static void Replace(string temporary, string path, string what, bool syncFirst)
        {
            try
            {
                if (syncFirst)
                {
                    // Data on disk before the rename, so a crash cannot leave an empty file behind.
                    using var stream = new FileStream(temporary, FileMode.Open, FileAccess.Write, FileShare.None);
                    stream.Flush(flushToDisk: true);
                }
                if (File.Exists(path))
                {
                    try
                    {
                        File.Replace(temporary, path, null, ignoreMetadataErrors: true);
                        return;
                    }
                    catch (FileNotFoundException) when (File.Exists(temporary) && !File.Exists(path))
                    {
                        // The target was removed in the meantime: create it instead.
                    }
                }
                File.Move(temporary, path);
            }
            catch (Exception e) when (IsFileError(e))
            {
                DeleteQuietly(temporary);
                throw Failure(path, what, "cannot replace it", e);
            }
        }

        internal static void DeleteQuietly(string path)
        {
            try
            {
                File.Delete(path);
            }
            catch (Exception e) when (IsFileError(e))
            {
                // Nothing better to do: the caller reports the failure that brought it here.
            }
        }

        static void DisposeQuietly(Stream stream)
        {
            try
            {
                stream.Dispose();
            }
            catch (Exception e) when (IsFileError(e))
            {
                // Closing after a failed write repeats the failure; the first one is reported.
            }
        }
    }
}
