"""The demo's log as cars record it, for test_logs.py: SAE axes (by projection on the SAE axes,
not by the reader's table of signs), kN, degrees, km/h and percent, the speed at a tenth of the
rate; as ASAM MDF4 signals (asammdf) and as CAN frames encoded by cantools with the DBC below,
logged by python-can as BLF, ASC, candump and MDF4 bus logging."""
from __future__ import annotations

import math

import numpy as np

# ISO-W (TYDEX W) axes as the world's basis: x forward, y left, z up. The SAE J670 tyre axes
# in that basis: x forward, y right, z down.
SAE_X = np.array([1.0, 0.0, 0.0])
SAE_Y = np.array([0.0, -1.0, 0.0])
SAE_Z = np.array([0.0, 0.0, -1.0])

#: The speed is recorded at every SLOW-th row of the master (and at the last).
SLOW = 10


def slow_rows(n: int) -> np.ndarray:
    idx = np.arange(0, n, SLOW)
    return idx if idx[-1] == n - 1 else np.append(idx, n - 1)


def iso_to_sae(iso: dict) -> dict:
    """Physical vectors from their ISO-W components, then their components on the SAE axes:
    force F and moment M as vectors; the slip angle from the contact point's velocity direction
    (the angle from x to it, positive about each system's z); the inclination from the wheel
    plane's upward unit vector (positive when it leans towards each system's +y)."""
    out = {}
    f = np.stack([iso["fx"], iso["fy"], iso["fz"]], axis=-1)
    out["fx"], out["fy"], out["fz"] = f @ SAE_X, f @ SAE_Y, f @ SAE_Z
    m = np.stack([np.zeros_like(iso["mz"]), np.zeros_like(iso["mz"]), iso["mz"]], axis=-1)
    out["mz"] = m @ SAE_Z
    a = iso["alpha"]
    v = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=-1)  # tan α = Vsy/|Vx| (ISO-W)
    out["alpha"] = np.arctan2(v @ SAE_Y, v @ SAE_X)
    g = iso["gamma"]
    up = np.stack([np.zeros_like(g), np.sin(g), np.cos(g)], axis=-1)  # top leans to +y when γ > 0
    out["gamma"] = np.arcsin(np.clip(up @ SAE_Y, -1.0, 1.0))
    out["kappa"], out["vx"] = iso["kappa"], iso["vx"]
    return out


#: Channel name, unit, factor from SI, per gough column (the logger's view of the demo's log).
CHANNELS = {
    "fz": ("Fz_FL", "kN", 1e-3),
    "fy": ("Fy_FL", "kN", 1e-3),
    "mz": ("Mz_FL", "Nm", 1.0),
    "fx": ("Fx_FL", "kN", 1e-3),
    "kappa": ("Slip_FL", "%", 1e2),
    "alpha": ("Alpha_FL", "deg", 180.0 / math.pi),
    "gamma": ("Gamma_FL", "deg", 180.0 / math.pi),
    "vx": ("VehSpd", "km/h", 3.6),
}


def recorded(df) -> dict:
    """The demo's log (ISO-W, SI) as the logger records it: channel name -> values (SAE,
    logger's units)."""
    sae = iso_to_sae({c: df[c].to_numpy() for c in CHANNELS})
    return {name: sae[c] * k for c, (name, _, k) in CHANNELS.items()}


def write_mdf(df, path, units_in_file=True) -> None:
    """ASAM MDF4 with asammdf: each channel with its own time stamps (the speed at a tenth of
    the rate), in two channel groups as a logger with two rasters writes them."""
    from asammdf import MDF, Signal

    t = df["t"].to_numpy()
    rec = recorded(df)
    fast, slow = [], []
    for c, (name, unit, _) in CHANNELS.items():
        u = unit if units_in_file else ""
        if c == "vx":
            i = slow_rows(len(t))
            slow.append(Signal(rec[name][i], t[i], name=name, unit=u))
        else:
            fast.append(Signal(rec[name], t, name=name, unit=u))
    with MDF(version="4.10") as mdf:
        mdf.append(fast, comment="1 kHz")
        mdf.append(slow, comment="100 Hz")
        mdf.save(path, overwrite=True)


# The test's vehicle DBC: 32-bit scaled integers fine enough that quantisation (1 mN, 0.1 mN·m,
# 1e-8 slip, 1e-7 deg) is far below the log's own noise; the speed 16-bit, 0.01 km/h.
DBC = """VERSION ""

NS_ :

BS_:

BU_: LOGGER

BO_ 257 FL_Forces1: 8 LOGGER
 SG_ Fy_FL : 0|32@1- (1e-06,0) [-2000|2000] "kN" Vector__XXX
 SG_ Fz_FL : 32|32@1- (1e-06,0) [-2000|2000] "kN" Vector__XXX

BO_ 258 FL_Forces2: 8 LOGGER
 SG_ Mz_FL : 0|32@1- (0.0001,0) [-200000|200000] "Nm" Vector__XXX
 SG_ Fx_FL : 32|32@1- (1e-06,0) [-2000|2000] "kN" Vector__XXX

BO_ 259 FL_Slip: 8 LOGGER
 SG_ Slip_FL : 0|32@1- (1e-06,0) [-2000|2000] "%" Vector__XXX
 SG_ Alpha_FL : 32|32@1- (1e-07,0) [-200|200] "deg" Vector__XXX

BO_ 260 FL_Camber: 4 LOGGER
 SG_ Gamma_FL : 0|32@1- (1e-07,0) [-200|200] "deg" Vector__XXX

BO_ 512 Vehicle: 2 LOGGER
 SG_ VehSpd : 0|16@1+ (0.01,0) [0|655.35] "km/h" Vector__XXX

"""

#: The map of the bus logs (the DBC written next to it as vehicle.dbc).
BUS_MAP = """dbc = "vehicle.dbc"
convention = "SAE"
[time]
master = "fy"
[channels]
fz = { name = "FL_Forces1.Fz_FL", unit = "kN" }
fy = { name = "FL_Forces1.Fy_FL", unit = "kN" }
mz = { name = "FL_Forces2.Mz_FL", unit = "Nm" }
fx = { name = "FL_Forces2.Fx_FL", unit = "kN" }
kappa = { name = "FL_Slip.Slip_FL", unit = "%" }
alpha = { name = "FL_Slip.Alpha_FL", unit = "deg" }
gamma = { name = "FL_Camber.Gamma_FL", unit = "deg" }
vx = { name = "Vehicle.VehSpd", unit = "km/h" }
"""

#: The map of the MDF4 signal log.
MDF_MAP = """convention = "SAE"
[time]
master = "fy"
[channels]
""" + "".join(f'{c} = {{ name = "{n}", unit = "{u}" }}\n' for c, (n, u, _) in CHANNELS.items())


def frames(df):
    """The demo's log as python-can messages encoded by cantools with DBC, in time order."""
    import can
    import cantools

    db = cantools.database.load_string(DBC, "dbc")
    t = df["t"].to_numpy()
    rec = recorded(df)
    msgs = []
    groups = {m.name: [s.name for s in m.signals] for m in db.messages}
    slow = set(slow_rows(len(t)).tolist())
    for i in range(len(t)):
        for mname, sigs in groups.items():
            if mname == "Vehicle" and i not in slow:
                continue
            m = db.get_message_by_name(mname)
            # cantools rounds the physical value to the nearest raw integer.
            data = m.encode({s: float(rec[s][i]) for s in sigs})
            msgs.append(can.Message(timestamp=float(t[i]), arbitration_id=m.frame_id,
                                    is_extended_id=False, data=data, channel=0))
    return msgs


def write_bus(df, path) -> None:
    """The frames as a bus log; the format by the suffix (.blf, .asc, .log, .mf4)."""
    import can

    with can.Logger(str(path)) as log:
        for m in frames(df):
            log.on_message_received(m)
