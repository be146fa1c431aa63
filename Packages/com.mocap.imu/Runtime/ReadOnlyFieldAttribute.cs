using UnityEngine;

namespace Mocap.Imu
{
    /// <summary>
    /// A status field the component writes and the inspector only shows: drawn disabled (a text
    /// with <see cref="Lines"/> greater than 1 as a selectable multi-line box, so an error can be
    /// copied), never edited by hand.
    /// </summary>
    public sealed class ReadOnlyFieldAttribute : PropertyAttribute
    {
        /// <summary>Lines of text shown for a string (1: one line).</summary>
        public readonly int Lines;

        public ReadOnlyFieldAttribute(int lines = 1)
        {
            Lines = lines < 1 ? 1 : lines;
        }
    }
}
