"""silrig_client: fly a Python controller in a silrig run.

A thin ctypes wrapper over libsilrig_client.so (silrig's own controller session behind a C ABI; see
examples/c/silrig_client.h for the rules) with no third-party dependency. Write a `Controller` with one method,
`step(sample, dt_s)`, and hand it to `serve()`. Signals go by the names the plant announced: read an output as
`sample["theta_deg"]`, command inputs with a dict; an input you leave out stays where its actuator is:

    from silrig_client import Controller, serve

    class Hold(Controller):
        def step(self, sample, dt_s):
            return {"elevator": -2.0 - 0.5 * sample["q_dps"]}

    raise SystemExit(serve(Hold()))

and fly it with `silrig run --controller-cmd "python3 my_controller.py"`.

A plant of your own is a `PlantModel` (its signals, its outputs now, one step with given inputs) handed to
`serve_plant()`, flown with `silrig run --plant-cmd "python3 my_plant.py"`; the rig keeps the clock, the
watchdog, the failsafe and the faults around it (examples/python/jsbsim_plant.py flies JSBSim's aircraft). The launcher passes the run in SILRIG_*
variables and the library's path in SILRIG_CLIENT_LIB; by hand (`--controller external`), `. <out>/controller.env`
first.
"""

import ctypes
import os
import pathlib
import sys

from silrig_contract import (
    ERR_COMMAND_REFUSED,
    INPUT_COMMAND_IN_TRACE,
    MAX_INPUTS,
    NO_OUTPUT,
    NOT_GIVEN,
    OK,
    OUTPUT_IN_TRACE,
    RUN_ENDED,
    STOPPED,
    WIRE_LAYOUT_VERSION,
    CommandSample,
    PlantInfo,
    PlantSample,
)


class SilrigError(RuntimeError):
    """A call into libsilrig_client.so failed; `code` is one of the contract's ERR_* status codes."""

    def __init__(self, code, message):
        super().__init__(message)
        self.code = code


def _library_path():
    given = os.environ.get("SILRIG_CLIENT_LIB")
    if given:
        return given
    # A build tree: examples/python/ -> target/release/.
    built = pathlib.Path(__file__).resolve().parents[2] / "target" / "release" / "libsilrig_client.so"
    return str(built) if built.exists() else "libsilrig_client.so"


def _load():
    lib = ctypes.CDLL(_library_path())
    c_double_p = ctypes.POINTER(ctypes.c_double)
    session_p = ctypes.c_void_p
    signatures = {
        "silrig_layout_version": ([], ctypes.c_uint32),
        "silrig_last_error": ([], ctypes.c_char_p),
        "silrig_session_open": (
            [ctypes.c_uint32, ctypes.c_size_t, ctypes.c_size_t, ctypes.POINTER(ctypes.c_char_p), ctypes.c_size_t,
             ctypes.POINTER(session_p)],
            ctypes.c_int,
        ),
        "silrig_session_next_sample": ([session_p, ctypes.POINTER(PlantSample)], ctypes.c_int),
        "silrig_session_send_command": (
            [session_p, c_double_p, ctypes.c_size_t, c_double_p, ctypes.c_size_t],
            ctypes.c_int,
        ),
        "silrig_session_plant_info": ([session_p, ctypes.POINTER(PlantInfo)], ctypes.c_int),
        "silrig_session_signal_index": (
            [session_p, ctypes.c_char_p, ctypes.c_int, ctypes.POINTER(ctypes.c_size_t)],
            ctypes.c_int,
        ),
        "silrig_session_held_command": ([session_p, c_double_p, ctypes.c_size_t], ctypes.c_int),
        "silrig_plant_open": (
            [ctypes.c_uint32, ctypes.c_size_t, ctypes.c_size_t, ctypes.c_size_t, ctypes.POINTER(PlantInfo),
             ctypes.POINTER(session_p)],
            ctypes.c_int,
        ),
        "silrig_plant_tick": ([session_p, c_double_p, ctypes.c_size_t, c_double_p, ctypes.c_size_t], ctypes.c_int),
        "silrig_plant_dt_s": ([session_p], ctypes.c_double),
        "silrig_plant_parameter": ([ctypes.c_char_p, c_double_p], ctypes.c_int),
        "silrig_plant_restored_checkpoint": ([session_p], ctypes.c_char_p),
        "silrig_plant_checkpoint_used": ([session_p, ctypes.c_int, ctypes.c_char_p], ctypes.c_int),
        "silrig_plant_checkpoint_due": ([session_p], ctypes.c_int),
        "silrig_plant_save_checkpoint": ([session_p, ctypes.c_char_p], ctypes.c_int),
        "silrig_plant_close": ([session_p, ctypes.c_char_p], ctypes.c_int),
        "silrig_session_dt_s": ([session_p], ctypes.c_double),
        "silrig_session_setpoint_deg": ([session_p, c_double_p], ctypes.c_int),
        "silrig_session_setpoint": ([session_p, ctypes.c_char_p, c_double_p], ctypes.c_int),
        "silrig_session_restored_checkpoint": ([session_p], ctypes.c_char_p),
        "silrig_session_checkpoint_due": ([session_p], ctypes.c_int),
        "silrig_session_checkpoint_used": ([session_p, ctypes.c_int, ctypes.c_char_p], ctypes.c_int),
        "silrig_session_save_checkpoint": ([session_p, ctypes.c_char_p], ctypes.c_int),
        "silrig_session_close": ([session_p, ctypes.c_char_p], ctypes.c_int),
    }
    for name, (argtypes, restype) in signatures.items():
        function = getattr(lib, name)
        function.argtypes = argtypes
        function.restype = restype
    return lib


_lib = None


def library():
    """libsilrig_client.so, loaded once."""
    global _lib
    if _lib is None:
        _lib = _load()
    return _lib


def _check(code):
    if code < 0:
        raise SilrigError(code, library().silrig_last_error().decode(errors="replace"))
    return code


def _text(raw):
    return bytes(raw).split(b"\0", 1)[0].decode()


class Plant:
    """What the plant announced: `name`, `outputs` [(name, unit)], `inputs` [(name, unit, min, max, hold)]."""

    def __init__(self, info):
        self.name = _text(info.plant_name)
        self.outputs = [(_text(info.output_names[k]), _text(info.output_units[k])) for k in range(info.outputs_len)]
        self.inputs = [
            (_text(info.input_names[k]), _text(info.input_units[k]), info.input_min[k], info.input_max[k],
             info.input_hold[k])
            for k in range(info.inputs_len)
        ]
        self.output_index = {name: k for k, (name, _) in enumerate(self.outputs)}
        self.input_index = {i[0]: k for k, i in enumerate(self.inputs)}


class Sample:
    """A plant sample read by name: `sample["theta_deg"]`; `tick`, `t_s` and `raw` (the wire struct) beside."""

    __slots__ = ("raw", "_index")

    def __init__(self, raw, index):
        self.raw = raw
        self._index = index

    def __getitem__(self, name):
        try:
            k = self._index[name]
        except KeyError:
            # The plant's names beside the one asked for, as the package and the C ABI say it.
            raise KeyError(f"the plant has no output `{name}`; its outputs: {', '.join(self._index)}") from None
        return self.raw.outputs[k]

    @property
    def tick(self):
        return self.raw.header.tick

    @property
    def t_s(self):
        return self.raw.t_sim_s


class Session:
    """The controller's side of one run: `next_sample()`, then one `send()` per sample, then `close()`."""

    def __init__(self, diagnostic_names=()):
        lib = library()
        self._lib = lib
        self._handle = ctypes.c_void_p()
        names = [n.encode() for n in diagnostic_names]
        c_names = (ctypes.c_char_p * max(len(names), 1))(*names)
        _check(lib.silrig_session_open(
            WIRE_LAYOUT_VERSION, ctypes.sizeof(PlantSample), ctypes.sizeof(CommandSample), c_names, len(names),
            ctypes.byref(self._handle)))
        self._sample = PlantSample()
        self._sample_ref = ctypes.byref(self._sample)
        self._plant = None
        self._inputs = (ctypes.c_double * MAX_INPUTS)()
        self._diagnostics = (ctypes.c_double * max(len(names), 1))()
        self._diagnostic_count = len(names)
        #: Why the session stopped handing out samples: STOPPED or RUN_ENDED (None while it runs).
        self.stop_reason = None

    @property
    def dt_s(self):
        """The controller's step, s."""
        return self._lib.silrig_session_dt_s(self._handle)

    @property
    def setpoint_deg(self):
        """The scenario's attitude set point, deg: (roll, pitch, yaw)."""
        out = (ctypes.c_double * 3)()
        _check(self._lib.silrig_session_setpoint_deg(self._handle, out))
        return tuple(out)

    def setpoint(self, name, default=None):
        """The scenario's set point of output `name` (`[setpoint] alt_ft = 4000.0`), in its unit; `default` when the
        scenario gives none."""
        value = ctypes.c_double()
        if _check(self._lib.silrig_session_setpoint(self._handle, name.encode(), ctypes.byref(value))) == NOT_GIVEN:
            return default
        return value.value

    @property
    def plant(self):
        """The plant's announcement (a `Plant`), waiting for it if it has not come yet."""
        if self._plant is None:
            info = PlantInfo()
            _check(self._lib.silrig_session_plant_info(self._handle, ctypes.byref(info)))
            self._plant = Plant(info)
        return self._plant

    def output(self, name):
        """The index of output `name` in a sample's outputs; SilrigError (ERR_PLANT, naming the plant's outputs)
        when the plant has none of that name."""
        return self._signal_index(name, 0)

    def input(self, name):
        """The index of input `name` in a command; SilrigError (ERR_PLANT) when the plant has none."""
        return self._signal_index(name, 1)

    def _signal_index(self, name, is_input):
        index = ctypes.c_size_t()
        _check(self._lib.silrig_session_signal_index(self._handle, name.encode(), is_input, ctypes.byref(index)))
        return index.value

    def held_command(self):
        """A command that leaves every input where its actuator is now (one value per plant input)."""
        n = len(self.plant.inputs)
        _check(self._lib.silrig_session_held_command(self._handle, self._inputs, n))
        return list(self._inputs[:n])

    @property
    def restored_checkpoint(self):
        """What a predecessor saved (a restarted controller), or None."""
        text = self._lib.silrig_session_restored_checkpoint(self._handle)
        return None if text is None else text.decode()

    def next_sample(self):
        """The next plant sample to answer (a PlantSample, reused between calls: copy what you keep), or None when
        the run ended or a stop was requested (see `stop_reason`)."""
        code = _check(self._lib.silrig_session_next_sample(self._handle, self._sample_ref))
        if code == OK:
            return self._sample
        self.stop_reason = code
        return None

    def send(self, inputs, diagnostics=()):
        """Answer the sample: one value per plant input, in the plant's order, and one value per diagnostic name.
        Returns False when the command was refused (NaN, outside an input's range: the plant holds the last valid
        one); raises SilrigError on anything else."""
        buffer = self._inputs
        for i, value in enumerate(inputs):
            buffer[i] = value
        d = self._diagnostics
        for i, value in enumerate(diagnostics):
            d[i] = value
        code = self._lib.silrig_session_send_command(self._handle, buffer, len(inputs), d, len(diagnostics))
        if code == ERR_COMMAND_REFUSED:
            return False
        _check(code)
        return True

    def checkpoint_used(self, used, reason=None):
        """Say whether you resumed from `restored_checkpoint` (False: with the reason it did not fit)."""
        _check(self._lib.silrig_session_checkpoint_used(self._handle, int(bool(used)), None if reason is None else reason.encode()))

    def checkpoint_due(self):
        """Whether the session wants a checkpoint now."""
        return self._lib.silrig_session_checkpoint_due(self._handle) == 1

    def save_checkpoint(self, text):
        """Save the state a restarted controller resumes from."""
        _check(self._lib.silrig_session_save_checkpoint(self._handle, text.encode()))

    def close(self, error=None):
        """Write the controller's report and end the session (`error`: why your controller gave up, if it did)."""
        if self._handle:
            handle, self._handle = self._handle, ctypes.c_void_p()
            _check(self._lib.silrig_session_close(handle, None if error is None else str(error).encode()))

    def __enter__(self):
        return self

    def __exit__(self, kind, value, traceback):
        self.close(None if value is None else f"{kind.__name__}: {value}")
        return False


class Controller:
    """A controller for `serve()`: override `step`; the rest is optional."""

    #: Names of the diagnostics `step` returns (logged and plotted by the rig), 1..31 of [A-Za-z0-9_] each.
    diagnostic_names = ()

    def start(self, session):
        """Called once the session is open (read `session.setpoint_deg`, `session.dt_s`, `session.plant` here;
        `session.output(name)` fails early, naming the plant's outputs, when a signal you need is missing)."""

    def step(self, sample, dt_s):
        """One plant sample in (read it by name: `sample["theta_deg"]`); out, a dict of commands by input name
        (inputs left out stay where they are), or `(commands, diagnostics)`."""
        raise NotImplementedError

    def checkpoint(self):
        """The state a restarted controller should resume from, as text (None: nothing to save)."""
        return None

    def restore(self, text):
        """Resume from what `checkpoint` saved; return False if it does not fit."""
        return False


def serve(controller):
    """Fly `controller` until the run ends or SIGTERM; returns the process's exit status (0 clean, 1 error)."""
    try:
        session = Session(controller.diagnostic_names)
    except SilrigError as e:
        print(f"silrig_client: {e}", file=sys.stderr)
        return 2
    with session:
        saved = session.restored_checkpoint
        if saved is not None:
            # The session says in the run's events whether the controller resumed or started fresh.
            session.checkpoint_used(bool(controller.restore(saved)), "the controller's restore() returned False")
        controller.start(session)
        dt_s = session.dt_s
        plant = session.plant
        while True:
            raw = session.next_sample()
            if raw is None:
                return 0
            out = controller.step(Sample(raw, plant.output_index), dt_s)
            commands, diagnostics = out if isinstance(out, tuple) else (out, ())
            inputs = session.held_command()
            for name, value in commands.items():
                index = plant.input_index.get(name)
                # An unknown name: the library's error names the plant's inputs.
                inputs[session.input(name) if index is None else index] = value
            # False when refused: the run's events say why and the plant holds; the next sample may do better.
            session.send(inputs, diagnostics)
            if session.checkpoint_due():
                text = controller.checkpoint()
                if text is not None:
                    session.save_checkpoint(text)


class PlantModel:
    """A vehicle model for `serve_plant()`. Set `name`, `outputs` and `inputs`; implement `outputs_now` and `step`.

    outputs: [(name, unit)] or [(name, unit, in_trace)], in the order `outputs_now` returns them.
    inputs: [(name, unit, min, max, hold)] or with a sixth item, the name of the output that reports the
      actuator's position (the controller's session blends from it after a restart; the trace shows it after the
      commands); `hold` is what the rig's failsafe commands while no controller answers.
    """

    name = "plant"
    outputs = ()
    inputs = ()

    def start(self, dt_s):
        """Called once the session is open, with the run's step, s."""

    def outputs_now(self):
        """The outputs at this tick, one float per entry of `outputs`."""
        raise NotImplementedError

    def step(self, inputs, dt_s):
        """Advance the model by one period with these inputs (one float per entry of `inputs`)."""
        raise NotImplementedError

    def save(self):
        """The model's state as text, for a plant the launcher restarts (realtime); None: keep no checkpoint (a
        restarted plant then flies again from tick 0)."""
        return None

    def restore(self, text):
        """Take back the state `save` returned; raise to refuse it (the flight then starts again from tick 0)."""
        raise NotImplementedError("this model keeps no checkpoint")


def _put(field, text, what):
    """`text` NUL-padded into a name or unit field of the contract; too long is an error naming it."""
    data = text.encode()
    if len(data) >= len(field):
        raise ValueError(f"{what} {text!r} is {len(data)} bytes; the contract holds at most {len(field) - 1}")
    ctypes.memmove(field, data, len(data))


def plant_info(model):
    """The contract's PlantInfo for a PlantModel's name and signals (the library checks the rules and names any
    broken one)."""
    info = PlantInfo()
    info.header.layout_version = WIRE_LAYOUT_VERSION
    _put(info.plant_name, model.name, "plant name")
    info.outputs_len = len(model.outputs)
    info.inputs_len = len(model.inputs)
    output_index = {}
    for k, output in enumerate(model.outputs):
        name, unit = output[0], output[1]
        in_trace = output[2] if len(output) > 2 else True
        _put(info.output_names[k], name, "output name")
        _put(info.output_units[k], unit, f"unit of output {name}")
        info.output_flags[k] = OUTPUT_IN_TRACE if in_trace else 0
        output_index[name] = k
    for k, entry in enumerate(model.inputs):
        name, unit, low, high, hold = entry[:5]
        held = entry[5] if len(entry) > 5 else None
        _put(info.input_names[k], name, "input name")
        _put(info.input_units[k], unit, f"unit of input {name}")
        info.input_min[k], info.input_max[k], info.input_hold[k] = low, high, hold
        if held is not None and held not in output_index:
            raise ValueError(f"input {name}: its position output {held!r} is not among the plant's outputs")
        info.input_held_output[k] = NO_OUTPUT if held is None else output_index[held]
        info.input_flags[k] = INPUT_COMMAND_IN_TRACE
    return info


def plant_parameter(name, default):
    """The run's `[plant.parameters]` value of `name`, or `default` when the scenario gives none. Readable before
    the plant's session opens, so a model can start (trim) at it and announce the trim as its hold values."""
    value = ctypes.c_double()
    if _check(library().silrig_plant_parameter(name.encode(), ctypes.byref(value))) == NOT_GIVEN:
        return default
    return value.value


class PlantSession:
    """The plant's side of one run: `tick(outputs)` gives the inputs to step with, or None at the end."""

    def __init__(self, model):
        lib = library()
        self._lib = lib
        self._handle = ctypes.c_void_p()
        self._info = plant_info(model)
        _check(lib.silrig_plant_open(
            WIRE_LAYOUT_VERSION, ctypes.sizeof(PlantInfo), ctypes.sizeof(PlantSample), ctypes.sizeof(CommandSample),
            ctypes.byref(self._info), ctypes.byref(self._handle)))
        self._outputs = (ctypes.c_double * max(len(model.outputs), 1))()
        self._output_count = len(model.outputs)
        self._inputs = (ctypes.c_double * max(len(model.inputs), 1))()
        self._input_count = len(model.inputs)
        #: Why the session ended: STOPPED or RUN_ENDED (None while it runs).
        self.stop_reason = None

    @property
    def dt_s(self):
        """The run's step, s."""
        return self._lib.silrig_plant_dt_s(self._handle)

    @property
    def restored_checkpoint(self):
        """What a predecessor saved (a restarted plant), or None."""
        text = self._lib.silrig_plant_restored_checkpoint(self._handle)
        return None if text is None else text.decode()

    def checkpoint_used(self, used, reason=None):
        """Say whether the model restored `restored_checkpoint` (before the first tick)."""
        _check(self._lib.silrig_plant_checkpoint_used(self._handle, int(bool(used)),
                                                      None if reason is None else reason.encode()))

    @property
    def checkpoint_due(self):
        """True when the rig wants the model's state now (after stepping)."""
        return bool(self._lib.silrig_plant_checkpoint_due(self._handle))

    def save_checkpoint(self, text):
        _check(self._lib.silrig_plant_save_checkpoint(self._handle, text.encode()))

    def tick(self, outputs):
        """Hand in the outputs at this tick; the inputs to step with (a list), or None when the run is over."""
        buffer = self._outputs
        for i, value in enumerate(outputs):
            buffer[i] = value
        code = _check(self._lib.silrig_plant_tick(self._handle, buffer, len(outputs), self._inputs,
                                                  self._input_count))
        if code == OK:
            return self._inputs[:self._input_count]
        self.stop_reason = code
        return None

    def close(self, error=None):
        """Write the plant's report and end the session."""
        if self._handle:
            handle, self._handle = self._handle, ctypes.c_void_p()
            _check(self._lib.silrig_plant_close(handle, None if error is None else str(error).encode()))

    def __enter__(self):
        return self

    def __exit__(self, kind, value, traceback):
        self.close(None if value is None else f"{kind.__name__}: {value}")
        return False


def serve_plant(model):
    """Fly `model` as the run's plant until the run ends or SIGTERM; returns the process's exit status."""
    try:
        session = PlantSession(model)
    except (SilrigError, ValueError) as e:
        print(f"silrig_client: {e}", file=sys.stderr)
        return 2
    with session:
        dt_s = session.dt_s
        model.start(dt_s)
        saved = session.restored_checkpoint
        if saved is not None:
            try:
                model.restore(saved)
                session.checkpoint_used(True)
            except Exception as e:  # noqa: BLE001 - whatever the model refuses with, the flight starts over
                session.checkpoint_used(False, f"{type(e).__name__}: {e}")
        while True:
            inputs = session.tick(model.outputs_now())
            if inputs is None:
                return 0
            model.step(inputs, dt_s)
            if session.checkpoint_due:
                text = model.save()
                if text is not None:
                    session.save_checkpoint(text)
