#!/bin/sh
# Our controller (silrig-controller) as a controller command of the user's own, from the run's SILRIG_* variables:
# tests/sweep_warm.rs sweeps it through warm and cold rigs alike.
exec "$(dirname "$SILRIG_CLIENT_LIB")/silrig-controller" "$SILRIG_SCENARIO" --run-id "$SILRIG_RUN_ID" \
    --mode "$SILRIG_MODE" --out "$SILRIG_OUT"
