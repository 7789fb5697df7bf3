"""Print the arm's joint positions from the running cell (run from the repository root)."""
import ctypes, iceoryx2 as iox2

class JointState(ctypes.Structure):  # phri::JointState, ipc-schema/src/messages.rs
    _fields_ = [("seq", ctypes.c_uint64), ("stamp_ns", ctypes.c_uint64), ("published_ns", ctypes.c_uint64),
                ("dof", ctypes.c_uint32), ("status", ctypes.c_uint32), ("q", ctypes.c_double * 12),
                ("tau", ctypes.c_double * 12), ("wrench", ctypes.c_double * 6), ("command_seq", ctypes.c_uint64),
                ("missed_commands", ctypes.c_uint32), ("_pad", ctypes.c_uint32)]
    @staticmethod
    def type_name(): return "phri::JointState"

node = iox2.NodeBuilder.new().create(iox2.ServiceType.Ipc)
sub = node.service_builder(iox2.ServiceName.new("robot/state")).publish_subscribe(JointState).open().subscriber_builder().create()
while node.wait(iox2.Duration.from_millis(100)) is None:
    while (sample := sub.receive()) is not None:
        s = sample.payload().contents
        print(s.seq, [round(x, 3) for x in s.q[:s.dof]])
