//! The stop signals of a YARP program (`yarpdev`, `yarprobotinterface`, the iKin
//! controllers): SIGINT and SIGTERM, each handed to the program's own policy.

use tokio::signal::unix::{signal, SignalKind};

/// Installs SIGINT and SIGTERM handlers now, so that a signal that comes early is not lost,
/// and calls `on_signal("SIGINT" | "SIGTERM")` for every one that comes, from a thread of
/// its own. What a signal does (stop at the first, abort at the fourth) is the caller's.
pub fn on_signals(mut on_signal: impl FnMut(&'static str) + Send + 'static) -> std::io::Result<()> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let (mut int, mut term) = {
        let _guard = rt.enter();
        (
            signal(SignalKind::interrupt())?,
            signal(SignalKind::terminate())?,
        )
    };
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            rt.block_on(async move {
                loop {
                    let which = tokio::select! {
                        _ = int.recv() => "SIGINT",
                        _ = term.recv() => "SIGTERM",
                    };
                    on_signal(which);
                }
            })
        })?;
    Ok(())
}
