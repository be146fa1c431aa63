/* libFuzzer target for the calibration file reader (calib_load).
 *
 * Invariants, any violation aborts:
 *  1. A refused file leaves the caller's calibration untouched and sets a non-empty error text.
 *  2. Whatever calib_load accepts, calib_save accepts too (the reader checks at least what the
 *     writer checks), and loading the saved file gives back the identical calibration. */
#include "calibration.h"
#include "fuzz_file_support.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[600], saved[600];
    fuzz_write_file("input.calibration", data, size, path, sizeof path);

    mocap_calibration loaded, sentinel;
    memset(&sentinel, 0xA5, sizeof sentinel);
    loaded = sentinel;
    mocap_status st = calib_load(path, &loaded);
    if (st != MOCAP_OK) {
        fuzz_check(memcmp(&loaded, &sentinel, sizeof loaded) == 0);
        fuzz_check(mocap_last_error() != NULL && mocap_last_error()[0] != '\0');
        return 0;
    }
    snprintf(saved, sizeof saved, "%s/saved.calibration", fuzz_scratch_dir());
    fuzz_check(calib_save(&loaded, saved) == MOCAP_OK);
    mocap_calibration again;
    memset(&again, 0x5A, sizeof again);
    fuzz_check(calib_load(saved, &again) == MOCAP_OK);
    fuzz_check(memcmp(&loaded, &again, sizeof loaded) == 0);
    return 0;
}
