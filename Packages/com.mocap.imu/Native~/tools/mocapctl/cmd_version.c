/* mocapctl version: the engine's version and API major version. */
#include <stdio.h>

#include "commands.h"
#include "mocap_imu.h"

int cmd_version(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    printf("mocapctl %s (API %d)\n", mocap_version_string(), mocap_api_version());
    return 0;
}
