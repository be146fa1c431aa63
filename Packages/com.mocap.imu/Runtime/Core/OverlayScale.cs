// How much the calibration overlay is magnified: IMGUI sizes are in pixels, so on a high-DPI
// screen a panel laid out for 96 dpi is small and hard to read.

using System;

namespace Mocap.Imu
{
    /// <summary>The scale factor of a pixel-sized overlay.</summary>
    public static class OverlayScale
    {
        /// <summary>The density IMGUI's default sizes are made for.</summary>
        public const float ReferenceDpi = 96f;

        /// <summary>The largest magnification (a 384 dpi phone-class panel).</summary>
        public const float MaxScale = 4f;

        /// <summary>
        /// dpi / 96, never below 1 (a low-density screen keeps the designed size) nor above
        /// <see cref="MaxScale"/>; 1 when the density is unknown (Unity reports 0) or not a number.
        /// Then reduced, down to 1 at least, so that the panel's bottom-right corner
        /// (<paramref name="panelRight"/>, <paramref name="panelBottom"/> in unscaled pixels) stays
        /// on a screen of the given size.
        /// </summary>
        public static float For(float dpi, float screenWidth, float screenHeight, float panelRight, float panelBottom)
        {
            float scale = float.IsNaN(dpi) || float.IsInfinity(dpi) || dpi <= 0f ? 1f : Math.Min(Math.Max(dpi / ReferenceDpi, 1f), MaxScale);
            if (panelRight > 0f && screenWidth > 0f) scale = Math.Min(scale, screenWidth / panelRight);
            if (panelBottom > 0f && screenHeight > 0f) scale = Math.Min(scale, screenHeight / panelBottom);
            return Math.Max(scale, 1f);
        }
    }
}
