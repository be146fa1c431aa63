// The calibration overlay's lines joined into one text for a world-space panel (the VR view,
// where a screen overlay is not seen). It is read every frame: the text is joined again only
// when one of its lines is another string than last time, so an unchanged panel allocates nothing.

using System;
using System.Text;

namespace Mocap.Imu
{
    /// <summary>Up to <see cref="Capacity"/> lines joined with newlines, rebuilt only when a line changes.</summary>
    public sealed class PanelText
    {
        readonly string[] _lines;
        readonly StringBuilder _builder = new StringBuilder(256);
        int _count;
        int _builtCount = -1;
        string _text = "";

        public PanelText(int capacity)
        {
            if (capacity <= 0) throw new ArgumentOutOfRangeException(nameof(capacity), capacity, "a panel holds at least one line");
            _lines = new string[capacity];
        }

        /// <summary>The most lines a text holds.</summary>
        public int Capacity => _lines.Length;

        /// <summary>Starts a new text; lines are then added in order with <see cref="Add"/>.</summary>
        public void Begin() => _count = 0;

        /// <summary>Adds a line (null: skipped). Lines beyond <see cref="Capacity"/> are an error.</summary>
        public void Add(string line)
        {
            if (line == null) return;
            if (_count == _lines.Length)
                throw new InvalidOperationException($"the panel holds {_lines.Length} lines; a line more was added");
            if (!ReferenceEquals(_lines[_count], line))
            {
                _lines[_count] = line;
                _builtCount = -1;
            }
            _count++;
        }

        /// <summary>The joined text of the lines added since <see cref="Begin"/>.</summary>
        public string Text
        {
            get
            {
                if (_builtCount == _count) return _text;
                _builder.Clear();
                for (int i = 0; i < _count; i++)
                {
                    if (i > 0) _builder.Append('\n');
                    _builder.Append(_lines[i]);
                }
                _text = _builder.ToString();
                _builtCount = _count;
                return _text;
            }
        }
    }
}
