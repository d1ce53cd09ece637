//! The device opens on whatever adapter the machine has (lavapipe in CI).
use flarebench_gpu::{AdapterChoice, GpuContext};

#[test]
fn a_device_opens_and_reports_its_adapter() {
    let ctx = GpuContext::new(AdapterChoice::Any).expect("a GPU adapter (lavapipe in CI)");
    eprintln!("{:?}", ctx.report);
    assert!(!ctx.report.name.is_empty());
    ctx.wait().unwrap();
}
