//! The animated exports' frames, written beside the simulation.
//!
//! Each step with frames due hands a [`Job`] (the guides' positions, and
//! the guides' groom when the stages change attributes) to a writer thread
//! over a channel of [`QUEUE`] jobs. That thread grows the render hair
//! (in the bake's thread pool), converts units and encodes each export's
//! frame while the solver runs the next steps, so a bake with render hair
//! or large exports keeps every core busy; the queue bounds the memory to a
//! few frames of guides. The frames are the same, in the same order, as if
//! written on the bake's thread, which is where they are written when the
//! bake has one thread (`--threads 1`: a farm slot of one core).
//!
//! A bake that stops early (an error, an interrupt) drops the pipe: the
//! writer thread stops before its next job and is joined, so no file is
//! written after the bake has removed its staged outputs.

use super::error::BakeError;
use super::render::Delivery;
use exporters::FrameWriter;
use groom::interpolate::RenderHair;
use groom::{Frame, Groom, Units, UpAxis};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::Arc;
use std::thread::JoinHandle;

/// Jobs waiting for the writer thread: enough to keep it busy while the
/// solver steps, few enough that memory stays a few frames of guides.
const QUEUE: usize = 2;

/// One animated export's writing side.
pub(super) struct ExportSink {
    pub delivery: Delivery,
    pub writer: Box<dyn FrameWriter>,
    pub units: Units,
    pub up: UpAxis,
    /// A guide cache: frames give the guides' points only.
    pub guides_only: bool,
}

/// The frames due after one step.
pub(super) struct Job {
    /// The guides' positions (metres, Y up).
    pub positions: Vec<[f32; 3]>,
    /// The guides' groom with the attributes the stages change, when they
    /// change any.
    pub guides: Option<Groom>,
    /// `(sink, time in seconds)` of each frame due, in the order to write.
    pub frames: Vec<(usize, f64)>,
}

/// What every job is written with.
pub(super) struct Sinks {
    pub sinks: Vec<ExportSink>,
    pub render: Option<Arc<RenderHair>>,
    pub frame_attributes: Vec<&'static str>,
    pub pool: Arc<rayon::ThreadPool>,
}

impl Sinks {
    fn write(&mut self, job: Job) -> Result<(), BakeError> {
        let render = self.render.as_deref();
        for (index, time) in job.frames {
            let Some(sink) = self.sinks.get_mut(index) else {
                continue;
            };
            let mut points = if sink.guides_only {
                job.positions.clone()
            } else {
                self.pool
                    .install(|| sink.delivery.points(render, &job.positions))
            };
            groom::convert_points(
                &mut points,
                (Units::METERS, UpAxis::Y),
                (sink.units, sink.up),
            );
            let attributes = job.guides.as_ref().map_or_else(Vec::new, |g| {
                if sink.guides_only {
                    return super::frame_attributes::of_guides(g, &self.frame_attributes);
                }
                self.pool.install(|| {
                    super::frame_attributes::delivered(
                        &sink.delivery,
                        render,
                        g,
                        &self.frame_attributes,
                    )
                })
            });
            sink.writer.write_frame(&Frame {
                time,
                points,
                attributes,
            })?;
        }
        Ok(())
    }
}

type Worker = JoinHandle<(Sinks, Result<(), BakeError>)>;

/// Where a bake sends its animated frames.
pub(super) enum FramePipe {
    /// Written on the bake's thread.
    Inline(Sinks),
    Thread {
        sender: Option<SyncSender<Job>>,
        worker: Option<Worker>,
        stop: Arc<AtomicBool>,
    },
}

impl FramePipe {
    /// A pipe to `sinks`: a writer thread, unless the bake's pool has one
    /// thread.
    pub fn new(sinks: Sinks) -> Result<FramePipe, BakeError> {
        if sinks.pool.current_num_threads() <= 1 || sinks.sinks.is_empty() {
            return Ok(FramePipe::Inline(sinks));
        }
        let (sender, receiver) = sync_channel::<Job>(QUEUE);
        let stop = Arc::new(AtomicBool::new(false));
        let worker_stop = Arc::clone(&stop);
        let worker = std::thread::Builder::new()
            .name("groombake-export".into())
            .spawn(move || run(sinks, receiver, &worker_stop))
            .map_err(|e| BakeError::Threads(format!("export writer thread: {e}")))?;
        Ok(FramePipe::Thread {
            sender: Some(sender),
            worker: Some(worker),
            stop,
        })
    }

    /// Writes (or queues) the frames of `job`. An error of an earlier job
    /// on the writer thread is returned here, at the next job.
    pub fn send(&mut self, job: Job) -> Result<(), BakeError> {
        match self {
            FramePipe::Inline(sinks) => sinks.write(job),
            FramePipe::Thread { sender, .. } => {
                let delivered = sender.as_ref().is_some_and(|s| s.send(job).is_ok());
                if delivered {
                    return Ok(());
                }
                // The writer stopped on an error: return it.
                self.join().map(|_| ())
            }
        }
    }

    /// Waits for every queued frame to be written; the sinks, to finish.
    pub fn finish(mut self) -> Result<Vec<ExportSink>, BakeError> {
        self.join()
    }

    fn join(&mut self) -> Result<Vec<ExportSink>, BakeError> {
        match self {
            FramePipe::Inline(sinks) => Ok(std::mem::take(&mut sinks.sinks)),
            FramePipe::Thread { sender, worker, .. } => {
                drop(sender.take());
                let Some(worker) = worker.take() else {
                    return Ok(Vec::new());
                };
                match worker.join() {
                    Ok((sinks, Ok(()))) => Ok(sinks.sinks),
                    Ok((_, Err(error))) => Err(error),
                    // A panic while writing is the bake's, as if inline.
                    Err(panic) => std::panic::resume_unwind(panic),
                }
            }
        }
    }
}

impl Drop for FramePipe {
    fn drop(&mut self) {
        // Nothing may be written once the bake has gone on to clean up: stop
        // the writer and wait for it. Its error or panic, if any, follows
        // from the bake's own, which is the one reported.
        if let FramePipe::Thread {
            sender,
            worker,
            stop,
        } = self
        {
            stop.store(true, Ordering::Relaxed);
            drop(sender.take());
            if let Some(worker) = worker.take() {
                let _ = worker.join();
            }
        }
    }
}

/// The writer thread: writes each job in turn until the bake closes the
/// channel, stops it, or a write fails.
fn run(mut sinks: Sinks, jobs: Receiver<Job>, stop: &AtomicBool) -> (Sinks, Result<(), BakeError>) {
    for job in jobs {
        if stop.load(Ordering::Relaxed) {
            break;
        }
        if let Err(error) = sinks.write(job) {
            return (sinks, Err(error));
        }
    }
    (sinks, Ok(()))
}
