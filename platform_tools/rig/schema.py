"""The rig description's types: what `config/rig.yaml` may say, with units and ranges.

Every class is a frozen dataclass; every number carries its unit in its name (``_mm``, ``_deg``,
``_g``, ``_v``, ``_w``, ``_hz``) and in its ``Annotated`` metadata. Numbers that come from a vendor
(the size of a bought part, its mass, its lens) are :class:`Sourced`: a value with the source it was
read from and how far to trust it, so that estimates stay visible (``platform_tools rig estimates``).
Design choices (a wall thickness, a baseline) are plain numbers: the rig description *is* their source.

Cross-field rules (a baseline wider than the camera, fits in order, parts that exist) live in
:mod:`platform_tools.rig.rules`; derived values (poses of optical frames, focal lengths in pixels)
in :mod:`platform_tools.rig.model`.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Annotated, Literal, Mapping, Optional, Union

from .typed import Ge, Gt, Le, Lt, Unit

# ----------------------------------------------------------------------------- units
Mm = Annotated[float, Unit("mm")]
PosMm = Annotated[float, Unit("mm"), Gt(0)]
Deg = Annotated[float, Unit("deg"), Ge(-360), Le(360)]
Vec3Mm = Annotated[tuple[float, float, float], Unit("mm")]
Vec3Deg = Annotated[tuple[float, float, float], Unit("deg"), Ge(-360), Le(360)]
Hz = Annotated[float, Unit("Hz"), Gt(0)]
Volt = Annotated[float, Unit("V"), Ge(0)]


class Confidence(enum.Enum):
    """How far to trust a vendor number, best first."""
    DATASHEET = "datasheet"        # read from the vendor's own drawing or datasheet
    MEASURED = "measured"          # measured on a real part or a public model of one
    SECOND_HAND = "second_hand"    # a vendor figure quoted by someone else
    ESTIMATE = "estimate"          # our guess: check on a real part and update


class PartKind(enum.Enum):
    STEREO_CAMERA = "stereo_camera"
    THERMAL_CAMERA = "thermal_camera"
    LENS = "lens"
    COMPUTER = "computer"
    CAPTURE_CARD = "capture_card"
    BATTERY = "battery"
    BATTERY_ADAPTER = "battery_adapter"
    FAN = "fan"
    SWITCH = "switch"
    BUTTON = "button"
    ANTENNA = "antenna"
    CONVERTER = "converter"
    FUSE = "fuse"
    SCREW = "screw"
    INSERT = "insert"
    STANDOFF = "standoff"                 # a hex spacer with a thread at each end (cad/bought/fasteners.yaml)
    GLAND = "gland"                       # a cable pass-through with strain relief
    CUTOFF = "cutoff"                     # an under-voltage disconnect
    INTERFACE_BOARD = "interface_board"   # a board that brings a camera's signals out to connectors


class Face(enum.Enum):
    """Faces of a part's envelope box, in the part's own frame (x forward, y left, z up)."""
    FRONT = "front"
    REAR = "rear"
    LEFT = "left"
    RIGHT = "right"
    TOP = "top"
    BOTTOM = "bottom"


# ----------------------------------------------------------------------------- provenance
@dataclass(frozen=True)
class Source:
    """Where vendor numbers were read."""
    title: str
    url: Optional[str] = None


@dataclass(frozen=True)
class Sourced:
    """A vendor number with its provenance: ``{value: 21, source: boson_groupgets, confidence: second_hand}``."""
    value: float
    source: str
    confidence: Confidence
    note: Optional[str] = None


SourcedMm = Annotated[Sourced, Unit("mm"), Gt(0)]
SourcedG = Annotated[Sourced, Unit("g"), Gt(0)]
SourcedW = Annotated[Sourced, Unit("W"), Ge(0)]


# ----------------------------------------------------------------------------- bought parts
@dataclass(frozen=True)
class Envelope:
    """The box a part occupies, in its own frame: x depth (forward), y width (left), z height (up)."""
    x: SourcedMm
    y: SourcedMm
    z: SourcedMm


@dataclass(frozen=True)
class MountingPattern:
    """Holes on one face of a part; positions are (u, v) from the face centre, in mm.

    u and v run along the face's two other axes in x, y, z order (a bottom face: u = x, v = y).
    """
    face: Face
    thread: str
    positions_mm: tuple[tuple[float, float], ...]
    depth_mm: PosMm
    source: str
    confidence: Confidence


@dataclass(frozen=True)
class VoltageRange:
    min: Volt
    max: Volt


@dataclass(frozen=True)
class SourcedVoltRange:
    """A vendor voltage range, each end with its provenance:
    ``{min: {value: 3, source: ..., confidence: ...}, max: {value: 12, ...}}``."""
    min: Annotated[Sourced, Unit("V"), Ge(0)]
    max: Annotated[Sourced, Unit("V"), Ge(0)]


@dataclass(frozen=True)
class Part:
    kind: PartKind
    vendor: str
    part_number: str
    description: str
    mass_g: SourcedG
    envelope_mm: Envelope
    power_w: Optional[SourcedW] = None
    supply_v: Optional[VoltageRange] = None
    output_v: Optional[VoltageRange] = None
    #: part-specific dimensions (a lens length, a rail width), each with its source
    dims: Mapping[str, Sourced] = field(default_factory=dict)
    mounting: tuple[MountingPattern, ...] = ()
    #: a camera's highest frame rate (what its external sync can be triggered at), with its source
    max_frame_rate_hz: Optional[Annotated[Sourced, Unit("Hz"), Gt(0)]] = None
    #: a camera's external-sync input: the trigger pulse levels it accepts, with their source
    sync_input_v: Optional[SourcedVoltRange] = None
    #: a switch's or fuse's DC current rating, a converter's output current rating, with its source
    rating_a: Optional[Annotated[Sourced, Unit("A"), Gt(0)]] = None
    #: the DC voltage a switch or fuse is rated to break, with its source
    rating_dc_v: Optional[Annotated[Sourced, Unit("V"), Gt(0)]] = None
    #: a converter's efficiency (0-1), with its source
    efficiency: Optional[Annotated[Sourced, Gt(0), Le(1)]] = None
    #: a battery's discharge cut-off: the load must stop at this voltage (a Makita pack relies on the tool)
    cutoff_v: Optional[Annotated[Sourced, Unit("V"), Gt(0)]] = None


# ----------------------------------------------------------------------------- cameras
@dataclass(frozen=True)
class CameraModelSpec:
    """Nominal optics of a camera: what a calibration starts from and synthetic images are made with."""
    width_px: Annotated[int, Gt(0)]
    height_px: Annotated[int, Gt(0)]
    pixel_pitch_um: Annotated[Sourced, Unit("um"), Gt(0)]
    focal_length_mm: Annotated[Sourced, Unit("mm"), Gt(0)]
    hfov_deg: Annotated[Sourced, Unit("deg"), Gt(0), Lt(180)]
    projection: Literal["pinhole", "fisheye"]
    fps: Hz
    vfov_deg: Optional[Annotated[Sourced, Unit("deg"), Gt(0), Lt(180)]] = None


@dataclass(frozen=True)
class PoseSpec:
    """A pose in a parent frame: translation in mm, then roll-pitch-yaw in degrees.

    rpy follows URDF: fixed axes x, y, z, so R = Rz(yaw) @ Ry(pitch) @ Rx(roll).
    """
    xyz_mm: Vec3Mm
    rpy_deg: Vec3Deg = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class StereoCameraSpec:
    """The ZED X. `pose` places its camera centre (midway between the optical centres) in the rig frame."""
    part: str
    camera_model: str
    pose: PoseSpec


@dataclass(frozen=True)
class ThermalCameraSpec:
    #: Boson camera serial number (bosonGetCameraSN); null until the rig is built
    serial: Optional[Annotated[int, Gt(0)]]
    #: stable device name given by udev (/dev/<name>)
    device_name: str


@dataclass(frozen=True)
class ThermalPairSpec:
    """The Boson stereo pair. `pose` places the midpoint between the two optical centres in the rig frame;
    left is at +baseline/2 along the pair's y axis (the rig's left when looking forward)."""
    part: str
    lens: str
    camera_model: str
    baseline_mm: PosMm
    pose: PoseSpec
    left: ThermalCameraSpec
    right: ThermalCameraSpec


@dataclass(frozen=True)
class Sensors:
    zed_x: StereoCameraSpec
    thermal: ThermalPairSpec


# ----------------------------------------------------------------------------- enclosure, printing
@dataclass(frozen=True)
class Fits:
    """Clearance per side, by name of fit."""
    press_mm: Annotated[float, Unit("mm"), Ge(0)]
    sliding_mm: PosMm
    loose_mm: PosMm


@dataclass(frozen=True)
class HoleSizes:
    """Printed clearance-hole diameters for one screw size, by fit."""
    close_mm: PosMm
    normal_mm: PosMm
    loose_mm: PosMm


@dataclass(frozen=True)
class Printer:
    name: str
    nozzle_mm: PosMm
    layer_mm: PosMm
    bed_mm: Annotated[tuple[float, float, float], Unit("mm"), Gt(0)]
    material: str
    density_g_cm3: Annotated[float, Unit("g/cm3"), Gt(0)]
    filament_diameter_mm: PosMm
    max_overhang_deg: Annotated[float, Unit("deg"), Gt(0), Lt(90)]
    max_bridge_mm: PosMm
    #: the thinnest wall as a multiple of the nozzle width
    min_wall_nozzles: Annotated[float, Ge(1)] = 2.0
    #: +- where a printed face or hole lands against its nominal position (the tolerance stack-up, cad/tolerances.py)
    tolerance_mm: Annotated[float, Unit("mm"), Ge(0)] = 0.2


@dataclass(frozen=True)
class Handles:
    top: bool
    sides: bool
    grip_diameter_mm: PosMm
    grip_length_mm: PosMm
    clearance_mm: PosMm  # room for the fingers between grip and case


@dataclass(frozen=True)
class Ergonomics:
    """What a hand and a table ask of the rig (cad/ergonomics.py); sources in config/rig.yaml."""
    #: clear span between a handle's posts (hand-tool handle guidelines: >= 100 mm, 125 mm with gloves)
    min_clear_span_mm: PosMm = 100.0
    #: how far a thumb reaches from the grip it holds to press the record button
    thumb_reach_mm: PosMm = 50.0
    #: the rig on a table must not tip when tilted this far in any direction
    min_tilt_deg: Annotated[float, Unit("deg"), Gt(0), Lt(90)] = 10.0


@dataclass(frozen=True)
class HeatSink:
    """The copper heat sink clamped around each Boson body (machined)."""
    material: str
    density_g_cm3: Annotated[float, Unit("g/cm3"), Gt(0)]
    wall_mm: PosMm
    fin_count: Annotated[int, Ge(1)]
    fin_thickness_mm: PosMm
    fin_height_mm: PosMm
    #: +- position of a machined face or hole (the stop, the tapped holes: cad/tolerances.py)
    tolerance_mm: Annotated[float, Unit("mm"), Ge(0)] = 0.1
    #: diametral clearance of the Boson body in the bore (the fit the drawing asks for)
    bore_clearance_mm: Annotated[float, Unit("mm"), Ge(0)] = 0.05
    #: the front stop the Boson's front face registers against: its thickness
    stop_mm: PosMm = 1.5


@dataclass(frozen=True)
class Vents:
    slot_width_mm: PosMm
    slot_length_mm: PosMm
    #: vent open area as a multiple of the fans' inlet area (at least 1); per air path, of its fan's free area
    min_area_ratio: Annotated[float, Ge(1)]
    #: clear height over a fan's inlet as a fraction of its diameter (h >= D/4: the ring pi D h = the disc pi D^2/4)
    inlet_gap_ratio: Annotated[float, Gt(0), Le(1)] = 0.25


@dataclass(frozen=True)
class Enclosure:
    wall_mm: PosMm
    corner_radius_mm: Annotated[float, Unit("mm"), Ge(0)]
    component_clearance_mm: PosMm
    heat_sink_gap_mm: PosMm
    split: Literal["horizontal", "front_back"]
    screw: str
    insert: str
    screw_fit: Literal["close", "normal", "loose"]
    handles: Handles
    heat_sink: HeatSink
    vents: Vents
    ergonomics: Ergonomics = Ergonomics()


@dataclass(frozen=True)
class Printing:
    printer: Printer
    fits: Fits
    holes: Mapping[str, HoleSizes]


# ----------------------------------------------------------------------------- on-device
@dataclass(frozen=True)
class Sync:
    """Hardware trigger from the capture card to both Bosons."""
    source_part: str
    connector: str
    signal_pin: Annotated[int, Gt(0)]
    ground_pin: Annotated[int, Gt(0)]
    level_v: Volt
    rate_hz: Hz
    edge: Literal["rising", "falling"]
    boson_mode: Literal["slave", "master", "disabled"]
    #: write the sync mode to the Bosons' flash (a slave without a trigger shows no video)
    persist: bool
    #: per thermal camera: where its header stamp falls after the ZED left's stamp of the same trigger
    #: (edge, exposure, USB transport, driver buffering). It decides which trigger exposed a frame when
    #: the recording holds no other evidence (platform_tools.dataset.trigger): keep it narrower than one
    #: trigger period, and measure it on the rig
    stamp_latency_ms: Mapping[str, "LatencyWindow"] = field(default_factory=dict)


@dataclass(frozen=True)
class LatencyWindow:
    """``{min: {value: 0, source: ..., confidence: ...}, max: {...}}`` in milliseconds."""
    min: Annotated[Sourced, Unit("ms")]
    max: Annotated[Sourced, Unit("ms")]


@dataclass(frozen=True)
class RecordButton:
    gpio_pin: Annotated[int, Gt(0), Le(40)]
    led_pin: Annotated[int, Gt(0), Le(40)]
    pin_numbering: Literal["BOARD", "BCM"]
    bounce_ms: Annotated[int, Ge(0)]
    long_press_s: Annotated[float, Gt(0)]


@dataclass(frozen=True)
class Recording:
    data_mount: str
    output_dir: str
    storage_format: Literal["mcap"]
    compression_preset: Literal["none", "fastwrite", "zstd_fast", "zstd_small"]
    split_size_gb: Annotated[float, Gt(0)]
    split_duration_s: Annotated[float, Gt(0)]
    cache_mb: Annotated[int, Gt(0)]
    min_free_gb: Annotated[float, Ge(0)]
    stop_grace_s: Annotated[float, Gt(0)]
    button: RecordButton
    #: what the data drive sustains for rosbag2 (reported 110-120 MB/s, platform.md); `firmware check`
    #: fails when the recorded topics' rate computed from the rig exceeds it
    write_budget_mb_per_s: Annotated[float, Gt(0)]


@dataclass(frozen=True)
class Thermal8Bit:
    """16-bit raw thermal to 8-bit, as the paper: min-max (with percentile clip), CLAHE, bilateral."""
    percentile_low: Annotated[float, Ge(0), Lt(50)]
    percentile_high: Annotated[float, Gt(50), Le(100)]
    clahe_clip_limit: Annotated[float, Gt(0)]
    clahe_tile_grid: Annotated[int, Gt(0)]
    bilateral_d: Annotated[int, Gt(0)]
    bilateral_sigma_color: Annotated[float, Gt(0)]
    bilateral_sigma_space: Annotated[float, Gt(0)]
    #: the percentile clip applies only to frames whose maximum is at or above this (FIReStereo's rule);
    #: below it, plain min-max
    clip_above_counts: Annotated[int, Ge(0), Le(65535)]


@dataclass(frozen=True)
class SyncLimits:
    """Pass/fail limits of `platform_tools sync-check` (issue 9)."""
    #: an interval above this times the nominal period is a drop
    drop_interval_factor: Annotated[float, Gt(1)]
    max_drop_percent: Annotated[float, Ge(0), Le(100)]
    #: p99 of |pairing residual - constant offset| (thermal pair, and ZED left to each thermal)
    max_pair_jitter_p99_ms: Annotated[float, Gt(0)]
    max_drift_ppm: Annotated[float, Gt(0)]


@dataclass(frozen=True)
class Processing:
    thermal_8bit: Thermal8Bit
    pair_rate_hz: Hz
    #: thermal frames dropped on each side of an FFC period
    ffc_margin_frames: Annotated[int, Ge(0)]
    #: frames of the four cameras pair when their stamps agree within this, after the constant
    #: offset between the cameras (measured per recording) is removed
    pair_tolerance_ms: Annotated[float, Gt(0)]
    #: registration z-buffer: a point splats onto a thermal pixel when its depth is within this of
    #: the nearest point there (the same surface); farther points are occluded
    zbuffer_tolerance_percent: Annotated[float, Gt(0), Lt(100)]
    sync_limits: SyncLimits
    #: zlib level of the export's PNGs through OpenCV's libpng (0 none .. 9 smallest); null: the export's own fast
    #: writer (platform_tools/dataset/encode.py: ISA-L deflate level 1, UP filter; about 3x faster than OpenCV's
    #: default and 10 % smaller, the same pixels; docs/dataset.md "Speed")
    png_compression_level: Optional[Annotated[int, Ge(0), Le(9)]] = None
    #: the export's ZED images: "as_recorded" writes a compressed topic's JPEG (or PNG) as the recording holds it,
    #: byte for byte (a raw topic as PNG), "png" decodes every one and writes it as PNG (docs/dataset.md "Speed")
    zed_images: Literal["as_recorded", "png"] = "as_recorded"


# ----------------------------------------------------------------------------- on-device stack (issue 8)
@dataclass(frozen=True)
class Topics:
    """ROS 2 topics the rig publishes and records. The ZED names follow zed-ros2-wrapper
    (/<camera_name>/zed_node/...); the thermal ones are this project's."""
    zed_left: str
    zed_right: str
    zed_depth: str
    zed_imu: str
    thermal_left: str
    thermal_right: str
    thermal_left_status: str
    thermal_right_status: str


@dataclass(frozen=True)
class Images:
    """Container images of the compose stack (built for L4T on the Orin)."""
    zed: str
    thermal: str
    tools: str


@dataclass(frozen=True)
class Downloads:
    """What the image builds download, and how each download is verified."""
    #: sha256 of the ZED SDK installer (download.stereolabs.com); null until `platform_tools firmware
    #: pin --refresh` runs where there is network: the zed image build refuses to run without it
    zed_sdk_sha256: Optional[str]
    #: the OpenPGP fingerprint of the ROS 2 apt key (the key file changes when its expiry is extended;
    #: the fingerprint does not)
    ros_apt_key_fingerprint: str


@dataclass(frozen=True)
class BaseImages:
    """Digests (sha256:...) of the base images the Dockerfiles start from; null: pinned by tag only
    until `platform_tools firmware pin --refresh` asks the registries (docs/on-device.md)."""
    l4t_jetpack_digest: Optional[str]
    ros_digest: Optional[str]


@dataclass(frozen=True)
class Watchdog:
    #: stop the recording cleanly when the data drive has less than this free
    stop_free_gb: Annotated[float, Ge(0)]
    check_period_s: Annotated[float, Gt(0)]


@dataclass(frozen=True)
class OnDevice:
    """The generated on-device configuration (firmware/) and the recorder service."""
    install_dir: str
    compose_project: str
    ros_distro: Literal["humble", "iron", "jazzy"]
    #: 0 is the domain every ROS 2 machine joins by default: `firmware check` fails on it
    ros_domain_id: Annotated[int, Ge(0), Le(232)]
    #: localhost: DDS discovers and talks only on the Orin; subnet: also to peers on its networks (Wi-Fi)
    dds_discovery: Literal["localhost", "subnet"]
    #: SROS2: every node in its enclave, keys from `rig-device sros2-keys` (Enforce strategy)
    sros2_enclaves: bool
    #: compose services allowed privileged mode and host pid (the ZED X: docs/on-device.md says why)
    privileged_services: tuple[str, ...]
    #: the unprivileged user the thermal and health containers run as
    container_uid: Annotated[int, Gt(0)]
    downloads: Downloads
    base_images: BaseImages
    images: Images
    topics: Topics
    #: zed-ros2-wrapper camera_name (its node namespace)
    zed_camera_name: str
    #: zed-ros2-wrapper general.pub_downscale_factor: raw HD1200 stereo is beyond what rosbag2 writes
    zed_pub_downscale_factor: Annotated[float, Ge(1)]
    zed_depth_mode: Literal["NONE", "PERFORMANCE", "QUALITY", "ULTRA", "NEURAL"]
    #: zed-ros2-wrapper depth.openni_depth_mode: depth as 16-bit millimetres instead of 32-bit metres
    zed_depth_openni: bool
    #: Boson telemetry rows appended to each frame (640x512 becomes 640x514)
    thermal_telemetry_rows: Annotated[int, Ge(0)]
    #: usb_cam V4L2 parameters to write to the Bosons (e.g. brightness: 50): none by default, so the
    #: driver leaves the cameras as `boson-config` set them (firmware/v4l2.py, docs/on-device.md)
    thermal_v4l2_controls: Mapping[str, Union[bool, int]]
    #: ROS camera_info YAML of each Boson from the thermal calibration (relative to the rig file);
    #: null: the nominal model is published as camera_info (firmware/camerainfo.py)
    thermal_camera_info_left: Optional[str]
    thermal_camera_info_right: Optional[str]
    gpio_chips: tuple[str, ...]
    #: the button pulls the pin to ground when pressed
    button_active_low: bool
    #: after SIGINT and stop_grace_s, SIGTERM then this long before SIGKILL
    recorder_term_grace_s: Annotated[float, Gt(0)]
    #: how long the pre-flight watches the Boson frame counters advance
    trigger_watch_s: Annotated[float, Gt(0)]
    watchdog: Watchdog


# ----------------------------------------------------------------------------- the whole rig
@dataclass(frozen=True)
class RigDescription:
    schema_version: Literal[1]
    name: str
    sources: Mapping[str, Source]
    parts: Mapping[str, Part]
    camera_models: Mapping[str, CameraModelSpec]
    sensors: Sensors
    enclosure: Enclosure
    printing: Printing
    sync: Sync
    recording: Recording
    processing: Processing
    on_device: OnDevice
