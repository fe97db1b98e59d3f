"""A controller for tests/clients.rs: leaves every input where the plant holds it and logs, as its diagnostics, the
set points it reads through the client library each sample: `theta_deg` at the sample's time
(`session.setpoint(name, t_s=...)`, silrig_session_setpoint_at) and at the start (silrig_session_setpoint)."""

import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "python"))
from silrig_client import Controller, serve  # noqa: E402


class SetpointReader(Controller):
    diagnostic_names = ("sp_theta_now_deg", "sp_theta_start_deg")

    def start(self, session):
        self.session = session
        if session.setpoint("no_such_output", default=-7.0, t_s=1.0) != -7.0:
            raise SystemExit("setpoint_reader: a set point the scenario does not give is not the default")

    def step(self, sample, dt_s):
        now = self.session.setpoint("theta_deg", t_s=sample.t_s)
        return {}, (now, self.session.setpoint("theta_deg"))


if __name__ == "__main__":
    sys.exit(serve(SetpointReader()))
