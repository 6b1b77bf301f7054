#!/usr/bin/env python3
"""make_dicom_seed.py OUT: the seed of fuzz_dicom_folder: two 8 x 8 CT slices 2 mm apart, as the
target reads them (a 4-byte little-endian length of the first file, the first file, the second).

Each slice is a DICOM Part 10 file (PS3.10 7.1: 128-byte preamble, "DICM", the file meta group) in
explicit VR little endian (1.2.840.10008.1.2.1) with the attributes ctsurg's reader needs (PS3.3
C.7.6.2 Image Plane, C.7.6.3 Image Pixel, C.11.1 Modality LUT)."""
import struct
import sys


def element(group, elem, vr, value):
    if isinstance(value, str):
        value = value.encode('ascii')
        if len(value) % 2:
            value += b'\0' if vr == 'UI' else b' '
    head = struct.pack('<HH', group, elem) + vr.encode('ascii')
    if vr in ('OB', 'OW', 'UN', 'SQ', 'UT'):
        return head + b'\0\0' + struct.pack('<I', len(value)) + value
    return head + struct.pack('<H', len(value)) + value


def us(v):
    return struct.pack('<H', v)


def slice_file(z, instance):
    sop_uid = '1.2.826.0.1.3680043.10.1017.%d' % instance
    meta_body = (element(0x0002, 0x0001, 'OB', b'\0\1') + element(0x0002, 0x0002, 'UI', '1.2.840.10008.5.1.4.1.1.2') +
                 element(0x0002, 0x0003, 'UI', sop_uid) + element(0x0002, 0x0010, 'UI', '1.2.840.10008.1.2.1'))
    meta = element(0x0002, 0x0000, 'UL', struct.pack('<I', len(meta_body))) + meta_body
    pixels = b''.join(struct.pack('<h', (x * 37 + y * 11 + instance * 5) % 200 - 100) for y in range(8) for x in range(8))
    body = b''.join([
        element(0x0008, 0x0008, 'CS', 'ORIGINAL\\PRIMARY\\AXIAL'),
        element(0x0008, 0x0016, 'UI', '1.2.840.10008.5.1.4.1.1.2'),
        element(0x0008, 0x0018, 'UI', sop_uid),
        element(0x0008, 0x0060, 'CS', 'CT'),
        element(0x0020, 0x000D, 'UI', '1.2.826.0.1.3680043.10.1017.1'),
        element(0x0020, 0x000E, 'UI', '1.2.826.0.1.3680043.10.1017.2'),
        element(0x0020, 0x0011, 'IS', '1'),
        element(0x0020, 0x0013, 'IS', str(instance)),
        element(0x0020, 0x0032, 'DS', '-5\\-5\\%d' % z),
        element(0x0020, 0x0037, 'DS', '1\\0\\0\\0\\1\\0'),
        element(0x0028, 0x0002, 'US', us(1)),
        element(0x0028, 0x0004, 'CS', 'MONOCHROME2'),
        element(0x0028, 0x0010, 'US', us(8)),
        element(0x0028, 0x0011, 'US', us(8)),
        element(0x0028, 0x0030, 'DS', '1.25\\1.25'),
        element(0x0028, 0x0100, 'US', us(16)),
        element(0x0028, 0x0101, 'US', us(16)),
        element(0x0028, 0x0102, 'US', us(15)),
        element(0x0028, 0x0103, 'US', us(1)),
        element(0x0028, 0x1052, 'DS', '-1024'),
        element(0x0028, 0x1053, 'DS', '1'),
        element(0x7FE0, 0x0010, 'OW', pixels),
    ])
    return b'\0' * 128 + b'DICM' + meta + body


first, second = slice_file(0, 1), slice_file(2, 2)
with open(sys.argv[1], 'wb') as f:
    f.write(struct.pack('<I', len(first)) + first + second)
