// The serial port a HiPNUC receiver shows up as, per OS. The receivers' USB side is a USB-serial
// bridge, usually a Silicon Labs CP210x or a WCH CH340, and each OS names such a port after its
// driver:
//   Windows  COMn, number given by the driver at first plug-in (COM1 is often a motherboard port)
//   Linux    /dev/ttyUSBn (usbserial drivers cp210x, ch341), /dev/ttyACMn (CDC-ACM devices)
//   macOS    /dev/cu.usbserial-<serial> (Apple's own CP210x/CH34x and FTDI drivers),
//            /dev/cu.SLAB_USBtoUART (Silicon Labs' driver), /dev/cu.wchusbserial<id> (WCH's driver),
//            /dev/cu.usbmodem<id> (CDC-ACM). cu.* rather than tty.*: opening tty.* waits for carrier detect.

using System;
using System.Collections.Generic;
using System.IO;

namespace Mocap.Imu
{
    /// <summary>Default and detected serial port names for the sensor receiver.</summary>
    public static class SerialPortDefaults
    {
        /// <summary>
        /// The port a new setting starts with: "COM3" on Windows, "/dev/ttyUSB0" on Linux and
        /// "/dev/cu.usbserial-0001" on macOS (a CP210x with the default serial number under Apple's driver).
        /// </summary>
        public static string DefaultPort(HostOs os) => os switch
        {
            HostOs.Windows => "COM3",
            HostOs.MacOS => "/dev/cu.usbserial-0001",
            HostOs.Linux => "/dev/ttyUSB0",
            _ => throw new ArgumentOutOfRangeException(nameof(os), os, "unknown OS"),
        };

        /// <summary>
        /// Whether <paramref name="port"/> is named like a USB-serial receiver port on <paramref name="os"/>
        /// (Windows: COMn with n at least 2; the others: see the file header). A full path or a bare
        /// device name ("ttyUSB0", "cu.SLAB_USBtoUART") both count.
        /// </summary>
        public static bool LooksLikeReceiver(HostOs os, string port)
        {
            if (string.IsNullOrEmpty(port)) return false;
            switch (os)
            {
                case HostOs.Windows:
                    return port.Length > 3 && port.StartsWith("COM", StringComparison.OrdinalIgnoreCase) &&
                           int.TryParse(port.Substring(3), out int number) && number >= 2 && port.IndexOf(' ') < 0;
                case HostOs.Linux:
                    return RankLinux(DeviceName(port)) >= 0;
                case HostOs.MacOS:
                    return RankMac(DeviceName(port)) >= 0;
                default:
                    throw new ArgumentOutOfRangeException(nameof(os), os, "unknown OS");
            }
        }

        /// <summary>
        /// The most likely receiver among the ports present (as listed by the OS, e.g.
        /// <c>SerialPort.GetPortNames()</c> or the entries of /dev), else <see cref="DefaultPort"/>.
        /// Preference: Linux ttyUSB before ttyACM; macOS a CP210x or CH340 name before usbmodem;
        /// Windows the lowest COM number from 2 on (COM1 is usually not USB). Ties go to the lowest
        /// number, then to name order, so the answer does not depend on the listing's order.
        /// Unix ports are returned as /dev paths.
        /// </summary>
        public static string Pick(HostOs os, IEnumerable<string> presentPorts)
        {
            string best = null;
            int bestRank = int.MaxValue;
            long bestNumber = long.MaxValue;
            if (presentPorts != null)
            {
                foreach (var port in presentPorts)
                {
                    if (!LooksLikeReceiver(os, port)) continue;
                    string name = os == HostOs.Windows ? port.ToUpperInvariant() : "/dev/" + DeviceName(port);
                    int rank = os switch
                    {
                        HostOs.Windows => 0,
                        HostOs.Linux => RankLinux(DeviceName(port)),
                        _ => RankMac(DeviceName(port)),
                    };
                    long number = TrailingNumber(name);
                    bool better = rank < bestRank || (rank == bestRank && number < bestNumber) ||
                                  (rank == bestRank && number == bestNumber && string.CompareOrdinal(name, best) < 0);
                    if (!better) continue;
                    best = name;
                    bestRank = rank;
                    bestNumber = number;
                }
            }
            return best ?? DefaultPort(os);
        }

        /// <summary>The device names in <paramref name="devFolder"/> (normally /dev), for <see cref="Pick"/>.</summary>
        public static string[] ListDevices(string devFolder)
        {
            if (devFolder == null) throw new ArgumentNullException(nameof(devFolder));
            try
            {
                var entries = Directory.GetFileSystemEntries(devFolder);
                for (int i = 0; i < entries.Length; i++) entries[i] = Path.GetFileName(entries[i]);
                return entries;
            }
            catch (Exception e) when (e is IOException || e is UnauthorizedAccessException)
            {
                throw new MocapException(MocapStatus.NotFound, $"cannot list serial devices in {devFolder}: {e.Message}", e);
            }
        }

        static string DeviceName(string port)
        {
            string name = port.Replace('\\', '/');
            return name.StartsWith("/dev/", StringComparison.Ordinal) ? name.Substring(5) : name;
        }

        // Lower is likelier; -1 is not a receiver port.
        static int RankLinux(string name)
        {
            if (name.IndexOf('/') >= 0) return -1;
            if (HasNumberAfter(name, "ttyUSB")) return 0;
            if (HasNumberAfter(name, "ttyACM")) return 1;
            return -1;
        }

        static int RankMac(string name)
        {
            if (name.IndexOf('/') >= 0) return -1;
            if (name.StartsWith("cu.SLAB_USBtoUART", StringComparison.Ordinal)) return 0;
            if (name.StartsWith("cu.usbserial", StringComparison.Ordinal)) return 0;
            if (name.StartsWith("cu.wchusbserial", StringComparison.Ordinal)) return 0;
            if (name.StartsWith("cu.usbmodem", StringComparison.Ordinal)) return 1;
            return -1;
        }

        static bool HasNumberAfter(string name, string prefix)
        {
            if (!name.StartsWith(prefix, StringComparison.Ordinal) || name.Length == prefix.Length) return false;
            for (int i = prefix.Length; i < name.Length; i++)
                if (name[i] < '0' || name[i] > '9') return false;
            return true;
        }

        static long TrailingNumber(string name)
        {
            int start = name.Length;
            while (start > 0 && name[start - 1] >= '0' && name[start - 1] <= '9') start--;
            if (start == name.Length || name.Length - start > 18) return long.MaxValue;
            return long.Parse(name.Substring(start), System.Globalization.CultureInfo.InvariantCulture);
        }
    }
}
