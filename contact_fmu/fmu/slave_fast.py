"""The compiled path of the pythonfmu adapter: the model's compiled step and, where the
CPython extension is built, the per-step FMI calls in C (native/fmi.c).

A mixin of ContactSlave (slave.py). Where the model offers a compiled step
(``model.fast()``: the body model on the stepper, contact_fmu/native), the state lives
in its struct while it steps: ``_fast_enable`` binds it, the Real outputs are read
straight from the struct, and the extension's do_step, set_real and get_real take the
instance's place of the class's methods (handing everything they decline to them).
Python hands the state over before it reads or steps the model itself
(``_fast_pull``) and after it changed it (``_fast_push``), with the same doubles.
"""

from __future__ import annotations

from functools import partial
from operator import getitem

from .call_state import TIME_RTOL

# the FMI calls a compiled binding takes over (native/fmi.c)
FMI_CALLS = ("do_step", "set_real", "get_real")


class FastPathMixin:
    """ContactSlave's compiled path (its attributes are the adapter's: ``_fast*``,
    ``_call``, ``_out``, ``_input_slots``)."""

    def _fast_enable(self) -> None:
        """Use the model's compiled step if it has one (and the FMU no feedthrough)."""
        fast = getattr(self._model, "fast", None)
        compiled = fast is not None and not self._model.feedthrough and not self._terminated
        self._fast = fast() if compiled else None
        self._fast_out, self._fast_step, self._call.out_stale = None, None, False
        self._fast_io, self._fast_inputs, self._fast_reads = None, frozenset(), {}
        for name in FMI_CALLS:  # the class's methods again
            self.__dict__.pop(name, None)
        self._fast_fmi = None
        reals = {  # the registered Real outputs, by value reference
            vr: v
            for vr, v in self.vars.items()
            if v.name in self._out and self._vars[v.name].type == "Real"
        }
        if self._fast is None:
            for v in reals.values():
                v.getter = self._getters[v.name]
            return
        self._fast_out, self._fast_step = self._fast.io.out, self._fast.stepper()
        self._fast_io, self._fast_inputs = self._fast.io, frozenset(self._fast.INPUTS)
        self._fast_index = {n: self._fast.index(n) for n in self._out}
        self._fast_vr = {vr: self._fast_index[v.name] for vr, v in reals.items()}
        for v in reals.values():  # read straight from the struct: no Python frame per value
            v.getter = partial(getitem, self._fast_out, self._fast_index[v.name])
        self._fast_push()
        # the per-step FMI calls in C where the extension is built (native/fmi.c): on the
        # instance, in place of the class's methods, to which they hand all else (a step
        # to the Python path: the binding has just tried the compiled one)
        cls = type(self)
        methods = (self._python_step, cls.set_real.__get__(self), cls.get_real.__get__(self))
        slots = [(vr, *slot) for vr, slot in self._input_slots.items()]
        outs = [(vr, v.name) for vr, v in reals.items()]
        self._fast_fmi = self._fast.bind_fmi(self._call, methods, TIME_RTOL, slots, outs)
        if self._fast_fmi is not None:
            for name in FMI_CALLS:
                setattr(self, name, getattr(self._fast_fmi, name))

    def _fast_push(self) -> None:
        """After Python changed the model: its state, the inputs and the outputs (those
        of _out, as Python computed them) into the compiled step's struct."""
        self._fast.push()
        for n, v in self._call.inputs.items():
            self._to_fast(n, v)
        for n, i in self._fast_index.items():
            self._fast_out[i] = self._out[n]

    def _fast_pull(self) -> None:
        """Before Python reads or steps the model: the state and outputs back."""
        if self._fast is not None:
            self._fast.pull()
            self._sync_out()

    def _sync_out(self) -> None:
        if self._call.out_stale:
            self._out = {n: self._fast_out[i] for n, i in self._fast_index.items()}
            self._out_mu = self._call.values.get("mu")  # _tune pulls before mu changes
            self._call.out_stale = False
