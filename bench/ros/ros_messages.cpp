#include "bench/ros/ros_messages.hpp"

#include <string>

namespace rotolidar::bench::rosmsg {
namespace {

void WriteHeader(RosWriter& w, const RosHeader& h) {
  w.U32(h.seq);
  w.Time(h.stamp);
  w.String(h.frame_id);
}

RosHeader ReadHeader(RosReader& r) {
  RosHeader h;
  h.seq = r.U32("header.seq");
  h.stamp = r.Time("header.stamp");
  h.frame_id = r.String("header.frame_id");
  return h;
}

template <std::size_t N>
void WriteF64s(RosWriter& w, const std::array<double, N>& a) {
  for (double v : a) w.F64(v);
}

template <std::size_t N>
void ReadF64s(RosReader& r, const char* field, std::array<double, N>* a) {
  for (double& v : *a) v = r.F64(field);
}

void WriteF64Vector(RosWriter& w, const std::vector<double>& v) {
  w.U32(static_cast<uint32_t>(v.size()));
  for (double x : v) w.F64(x);
}

std::vector<double> ReadF64Vector(RosReader& r, const char* field) {
  std::vector<double> v(r.Count(field, 8));
  for (double& x : v) x = r.F64(field);
  return v;
}

void WriteByteVector(RosWriter& w, const std::vector<uint8_t>& v) {
  w.U32(static_cast<uint32_t>(v.size()));
  w.Bytes(v.data(), v.size());
}

std::vector<uint8_t> ReadByteVector(RosReader& r, const char* field) {
  std::vector<uint8_t> v(r.Count(field, 1));
  r.Bytes(field, v.size(), v.data());
  return v;
}

}  // namespace

std::vector<uint8_t> Serialize(const VelodyneScanMsg& m) {
  RosWriter w;
  WriteHeader(w, m.header);
  w.U32(static_cast<uint32_t>(m.packets.size()));
  for (const VelodynePacketMsg& p : m.packets) {
    w.Time(p.stamp);
    w.Bytes(p.data.data(), p.data.size());
  }
  return std::move(w.bytes());
}

Status Parse(const std::vector<uint8_t>& body, VelodyneScanMsg* out) {
  RosReader r(body.data(), body.size());
  out->header = ReadHeader(r);
  out->packets.resize(r.Count("packets", 8 + kVelodynePacketBytes));
  for (VelodynePacketMsg& p : out->packets) {
    p.stamp = r.Time("packets[].stamp");
    r.Bytes("packets[].data", p.data.size(), p.data.data());
  }
  return r.Finish();
}

std::vector<uint8_t> Serialize(const ImuMsg& m) {
  RosWriter w;
  WriteHeader(w, m.header);
  WriteF64s(w, m.orientation_xyzw);
  WriteF64s(w, m.orientation_covariance);
  WriteF64s(w, m.angular_velocity);
  WriteF64s(w, m.angular_velocity_covariance);
  WriteF64s(w, m.linear_acceleration);
  WriteF64s(w, m.linear_acceleration_covariance);
  return std::move(w.bytes());
}

Status Parse(const std::vector<uint8_t>& body, ImuMsg* out) {
  RosReader r(body.data(), body.size());
  out->header = ReadHeader(r);
  ReadF64s(r, "orientation", &out->orientation_xyzw);
  ReadF64s(r, "orientation_covariance", &out->orientation_covariance);
  ReadF64s(r, "angular_velocity", &out->angular_velocity);
  ReadF64s(r, "angular_velocity_covariance", &out->angular_velocity_covariance);
  ReadF64s(r, "linear_acceleration", &out->linear_acceleration);
  ReadF64s(r, "linear_acceleration_covariance", &out->linear_acceleration_covariance);
  return r.Finish();
}

std::vector<uint8_t> Serialize(const ImageMsg& m) {
  RosWriter w;
  WriteHeader(w, m.header);
  w.U32(m.height);
  w.U32(m.width);
  w.String(m.encoding);
  w.U8(m.is_bigendian);
  w.U32(m.step);
  WriteByteVector(w, m.data);
  return std::move(w.bytes());
}

Status Parse(const std::vector<uint8_t>& body, ImageMsg* out) {
  RosReader r(body.data(), body.size());
  out->header = ReadHeader(r);
  out->height = r.U32("height");
  out->width = r.U32("width");
  out->encoding = r.String("encoding");
  out->is_bigendian = r.U8("is_bigendian");
  out->step = r.U32("step");
  out->data = ReadByteVector(r, "data");
  return r.Finish();
}

std::vector<uint8_t> Serialize(const JointStateMsg& m) {
  RosWriter w;
  WriteHeader(w, m.header);
  w.U32(static_cast<uint32_t>(m.name.size()));
  for (const std::string& n : m.name) w.String(n);
  WriteF64Vector(w, m.position);
  WriteF64Vector(w, m.velocity);
  WriteF64Vector(w, m.effort);
  return std::move(w.bytes());
}

Status Parse(const std::vector<uint8_t>& body, JointStateMsg* out) {
  RosReader r(body.data(), body.size());
  out->header = ReadHeader(r);
  out->name.resize(r.Count("name", 4));
  for (std::string& n : out->name) n = r.String("name[]");
  out->position = ReadF64Vector(r, "position");
  out->velocity = ReadF64Vector(r, "velocity");
  out->effort = ReadF64Vector(r, "effort");
  return r.Finish();
}

std::vector<uint8_t> Serialize(const PointCloud2Msg& m) {
  RosWriter w;
  WriteHeader(w, m.header);
  w.U32(m.height);
  w.U32(m.width);
  w.U32(static_cast<uint32_t>(m.fields.size()));
  for (const PointFieldMsg& f : m.fields) {
    w.String(f.name);
    w.U32(f.offset);
    w.U8(f.datatype);
    w.U32(f.count);
  }
  w.U8(m.is_bigendian);
  w.U32(m.point_step);
  w.U32(m.row_step);
  WriteByteVector(w, m.data);
  w.U8(m.is_dense);
  return std::move(w.bytes());
}

Status Parse(const std::vector<uint8_t>& body, PointCloud2Msg* out) {
  RosReader r(body.data(), body.size());
  out->header = ReadHeader(r);
  out->height = r.U32("height");
  out->width = r.U32("width");
  out->fields.resize(r.Count("fields", 13));
  for (PointFieldMsg& f : out->fields) {
    f.name = r.String("fields[].name");
    f.offset = r.U32("fields[].offset");
    f.datatype = r.U8("fields[].datatype");
    f.count = r.U32("fields[].count");
  }
  out->is_bigendian = r.U8("is_bigendian");
  out->point_step = r.U32("point_step");
  out->row_step = r.U32("row_step");
  out->data = ReadByteVector(r, "data");
  out->is_dense = r.U8("is_dense");
  return r.Finish();
}

std::vector<uint8_t> Serialize(const OdometryMsg& m) {
  RosWriter w;
  WriteHeader(w, m.header);
  w.String(m.child_frame_id);
  WriteF64s(w, m.position);
  WriteF64s(w, m.orientation_xyzw);
  WriteF64s(w, m.pose_covariance);
  WriteF64s(w, m.linear_velocity);
  WriteF64s(w, m.angular_velocity);
  WriteF64s(w, m.twist_covariance);
  return std::move(w.bytes());
}

Status Parse(const std::vector<uint8_t>& body, OdometryMsg* out) {
  RosReader r(body.data(), body.size());
  out->header = ReadHeader(r);
  out->child_frame_id = r.String("child_frame_id");
  ReadF64s(r, "pose.pose.position", &out->position);
  ReadF64s(r, "pose.pose.orientation", &out->orientation_xyzw);
  ReadF64s(r, "pose.covariance", &out->pose_covariance);
  ReadF64s(r, "twist.twist.linear", &out->linear_velocity);
  ReadF64s(r, "twist.twist.angular", &out->angular_velocity);
  ReadF64s(r, "twist.covariance", &out->twist_covariance);
  return r.Finish();
}

std::vector<uint8_t> Serialize(const TFMessageMsg& m) {
  RosWriter w;
  w.U32(static_cast<uint32_t>(m.transforms.size()));
  for (const TransformStampedMsg& t : m.transforms) {
    WriteHeader(w, t.header);
    w.String(t.child_frame_id);
    WriteF64s(w, t.translation);
    WriteF64s(w, t.rotation_xyzw);
  }
  return std::move(w.bytes());
}

Status Parse(const std::vector<uint8_t>& body, TFMessageMsg* out) {
  RosReader r(body.data(), body.size());
  out->transforms.resize(r.Count("transforms", 4 + 8 + 4 + 4 + 56));
  for (TransformStampedMsg& t : out->transforms) {
    t.header = ReadHeader(r);
    t.child_frame_id = r.String("transforms[].child_frame_id");
    ReadF64s(r, "transforms[].transform.translation", &t.translation);
    ReadF64s(r, "transforms[].transform.rotation", &t.rotation_xyzw);
  }
  return r.Finish();
}

}  // namespace rotolidar::bench::rosmsg
