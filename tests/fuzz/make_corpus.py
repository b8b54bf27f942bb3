#!/usr/bin/env python3
"""Writes the seed corpus of every fuzz target into tests/fuzz/corpus/<target>/ (small, committed files).

Valid inputs in each format, plus a few near misses. Run from anywhere: python3 tests/fuzz/make_corpus.py.
libFuzzer adds what it finds to a separate working folder; a crashing input found there is copied here by hand
together with its fix."""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CORPUS = os.path.join(HERE, "corpus")


def put(target, name, data):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


def vlp16_data(timestamp_us, azimuth0=0):
    """A single-return VLP-16 data packet (manual section 9): 12 blocks FF EE, azimuth, 32 x (distance, reflectivity)."""
    out = b""
    for b in range(12):
        az = (azimuth0 + 40 * b) % 36000
        out += b"\xff\xee" + struct.pack("<H", az)
        for ch in range(32):
            out += struct.pack("<HB", 2500 + 10 * ch, 50)  # 5 m
    return out + struct.pack("<I", timestamp_us) + b"\x37\x22"


def vlp16_position(timestamp_us):
    p = bytearray(512)
    p[198:202] = struct.pack("<I", timestamp_us)
    p[202] = 2  # PPS locked
    nmea = b"$GPRMC,120000,A,4807.038,N,01131.000,E,022.4,084.4,050626,003.1,W*6A\r\n"
    p[206:206 + len(nmea)] = nmea
    return bytes(p)


def pcap(payloads):
    out = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)
    for i, (port, payload) in enumerate(payloads):
        udp = struct.pack(">HHHH", port, port, 8 + len(payload), 0) + payload
        ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), i, 0x4000, 64, 17, 0, bytes([192, 168, 1, 201]),
                         bytes([255, 255, 255, 255])) + udp
        frame = b"\xff" * 6 + bytes([0x60, 0x76, 0x88, 0, 0, 1]) + b"\x08\x00" + ip
        out += struct.pack("<IIII", 1000, 1327 * i, len(frame), len(frame)) + frame
    return out


def rig_datagram(seq, records):
    out = b"RLRS" + bytes([1, len(records)]) + b"\0\0" + struct.pack("<II", seq, 0)
    for kind, count, t_ns, values in records:
        out += bytes([kind, 0, 0, 0]) + struct.pack("<Iq6d", count, t_ns, *values)
    return out


def main():
    d0, d1 = vlp16_data(1000000), vlp16_data(1001327, 480)
    put("vlp16_data", "valid", d0)
    put("vlp16_data", "bad_flag", b"\xff\xef" + d0[2:])
    put("vlp16_data", "short", d0[:600])
    put("vlp16_position", "valid", vlp16_position(1000000))
    put("vlp16_position", "no_nmea", bytes(512))
    put("raw_payloads", "two", d0 + d1)
    put("raw_payloads", "ragged", d0 + d1[:5])
    put("pcap", "two_packets", pcap([(2368, d0), (2368, d1)]))
    put("pcap", "position", pcap([(8308, vlp16_position(1000000)), (2368, d0)]))
    put("pcap", "truncated", pcap([(2368, d0)])[:700])
    put("rig_datagram", "imu_and_encoder",
        rig_datagram(7, [(1, 0, 5000000, (0.1, -0.2, 0.3, 0.0, 0.0, 9.81)), (2, 1234, 5001000, (0,) * 6)]))
    put("rig_datagram", "bad_type", rig_datagram(8, [(9, 0, 1, (0,) * 6)]))
    imu_header = "t_s,gyro_x_radps,gyro_y_radps,gyro_z_radps,accel_x_mps2,accel_y_mps2,accel_z_mps2\n"
    put("imu_csv", "valid", imu_header + "0.0,0,0,0,0,0,9.81\n0.005,0.1,0,0,0,0,9.8\n")
    put("imu_csv", "backwards", imu_header + "0.01,0,0,0,0,0,9.81\n0.005,0,0,0,0,0,9.8\n")
    put("imu_csv", "nan", imu_header + "0.0,nan,0,0,0,0,9.81\n")
    put("stream_csv", "encoder", "t_s,count\n0.0,5\n0.001,6\n0.002,4095\n")
    put("stream_csv", "camera", "t_s,index\n0.0,0\n0.033,1\n")
    put("calib_yaml", "minimal", "format_version: 1\nmotor_speed_radps: 2.6\n")
    put("calib_yaml", "poses", "format_version: 1\nT_base_motor: {translation_m: [0, 0, 0.1], rotation_wxyz: [1, 0, 0, 0]}\n"
        "encoder: {counts_per_rev: 4096, zero_offset_rad: 0.1}\nlidar: {elevation_deg: [1, 2]}\n")
    put("ply", "ascii", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n0 0 0\n1 2 3\n")
    put("ply", "binary", b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
        b"property float y\nproperty float z\nend_header\n" + struct.pack("<3f", 1, 2, 3))
    put("pcd", "ascii", "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n"
        "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n0 0 0\n1 2 3\n")
    put("kitti_bin", "two_points", struct.pack("<8f", 1, 2, 3, 0.5, 4, 5, 6, 0.1))
    put("kitti_text", "calib", "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: 1 0 0 0 0 1 0 0 0 0 1 0\n")
    put("kitti_text", "poses", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n")
    put("trajectory", "tum", "0.0 0 0 0 0 0 0 1\n0.1 1 0 0 0 0 0 1\n")
    put("trajectory", "euroc", "#timestamp_ns,p_x,p_y,p_z,q_w,q_x,q_y,q_z\n1000,0,0,0,1,0,0,0\n")
    put("slam_config", "visual", "cut_azimuth_deg: 10\nvisual: {enabled: true}\nwindow: {size: 5}\n")
    put("sim_config", "short", "duration_s: 1\nscene: box_room\nseed: 3\n")
    with open(os.path.join(ROOT, "scenes", "box_room.yaml"), "rb") as f:
        put("scene_yaml", "box_room", f.read())


if __name__ == "__main__":
    main()
